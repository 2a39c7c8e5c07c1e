#include <gtest/gtest.h>
#include <stdlib.h>

#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "scanstop_common/file_util.h"
#include "scanstop_mission/report.h"

namespace scanstop {
namespace mission {
namespace {

MissionState twoScans() {
  MissionState st;
  st.world = "room_10x8";
  st.state = State::Done;
  st.complete = true;
  st.complete_reason = "no frontier left";
  st.coverage = 0.97;
  st.collisions = 1;
  ScanRecord a;
  a.index = 0;
  a.true_pose = Pose2D();
  a.scan_time_s = 40.0;
  a.register_wall_s = 0.5;
  a.plan_wall_s = 0.0;
  ScanRecord b;
  b.index = 1;
  b.map_pose = Pose2D(2.03, 0.0, 0.01);
  b.odom_pose = Pose2D(2.30, 0.4, 0.1);
  b.true_pose = Pose2D(2.0, 0.0, 0.0);
  b.scan_time_s = 40.0;
  b.register_wall_s = 0.7;
  b.plan_wall_s = 0.3;
  b.converged = false;
  st.scans = {a, b};
  st.modelled_scan_s = 80.0;
  st.modelled_drive_s = 20.0;
  st.modelled_compute_s = 3.0;
  st.modelled_time_s = 103.0;
  return st;
}

TEST(Report, SummaryComputesErrorsAgainstGroundTruth) {
  const Summary s = summarize(twoScans());
  EXPECT_EQ(s.scans, 2);
  EXPECT_TRUE(s.has_ground_truth);
  EXPECT_NEAR(s.slam_error_m, 0.03, 1e-9);
  EXPECT_NEAR(s.slam_error_yaw_deg, 0.01 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(s.odom_error_m, 0.5, 1e-9);  // (0.3, 0.4) off
  EXPECT_NEAR(s.compute_per_cycle_mean_s, 0.75, 1e-9);
  EXPECT_NEAR(s.compute_per_cycle_max_s, 1.0, 1e-9);
  EXPECT_EQ(s.unconverged_registrations, 1);
}

TEST(Report, AteCoversEveryScanNotOnlyTheLast) {
  // The final pose can be right while scans on the way were far off: the ATE sees them.
  MissionState st = twoScans();
  ScanRecord c = st.scans.back();
  c.index = 2;
  c.map_pose = Pose2D(5.0, 1.0, 0.0);
  c.odom_pose = Pose2D(5.0, 1.0, 0.0);
  c.true_pose = Pose2D(5.0, 1.12, 0.0);  // 12 cm off
  ScanRecord d = st.scans.back();
  d.index = 3;
  d.map_pose = Pose2D(0.0, 0.0, 0.0);
  d.odom_pose = Pose2D(0.0, 0.0, 0.0);
  d.true_pose = Pose2D(0.0, 0.0, 0.0);  // back at the start, exact
  st.scans.push_back(c);
  st.scans.push_back(d);
  const Summary s = summarize(st);
  EXPECT_NEAR(s.slam_error_m, 0.0, 1e-12);  // the final error hides scan 2
  EXPECT_EQ(s.ate_scans, 4);
  EXPECT_NEAR(s.ate_max_m, 0.12, 1e-9);
  EXPECT_EQ(s.ate_max_scan, 2);
  EXPECT_NEAR(s.ate_rms_m, std::sqrt((0.03 * 0.03 + 0.12 * 0.12) / 4.0), 1e-9);
  EXPECT_NEAR(s.ate_yaw_max_deg, 0.01 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(s.odom_ate_max_m, 0.5, 1e-9);
  const std::string json = toJson(s);
  EXPECT_NE(json.find("\"ate_max_m\": 0.1200"), std::string::npos) << json;
  EXPECT_NE(json.find("\"ate_max_scan\": 2"), std::string::npos) << json;
  // A scan without a true pose (a real robot) does not count.
  st.scans[2].true_pose.reset();
  EXPECT_EQ(summarize(st).ate_scans, 3);
  EXPECT_NEAR(summarize(st).ate_max_m, 0.03, 1e-9);
}

TEST(Report, TrajectoryCsvHasEveryScanWithItsRegisteredAndFinalPose) {
  MissionState st = twoScans();
  st.scans[1].registered_pose = Pose2D(2.10, 0.0, 0.0);  // relaxation moved it to (2.03, 0, 0.01)
  const std::string csv = trajectoryCsv(st);
  std::istringstream in(csv);
  std::string header, line0, line1, extra;
  std::getline(in, header);
  std::getline(in, line0);
  std::getline(in, line1);
  EXPECT_FALSE(std::getline(in, extra));
  EXPECT_EQ(header.rfind("index,x,y,yaw,registered_x", 0), 0u) << header;
  EXPECT_EQ(line1.rfind("1,2.030000,0.000000,0.010000,2.100000,0.000000,0.000000,2.300000,0.400000,0.100000,"
                        "2.000000,0.000000,0.000000,0.030000,",
                        0),
            0u)
      << line1;
  // Without a relaxation the registered pose is the pose itself.
  EXPECT_EQ(line0.rfind("0,0.000000,0.000000,0.000000,0.000000,0.000000,0.000000,", 0), 0u) << line0;
}

TEST(Report, WritesSummaryPlotsAndIndex) {
  char pattern[] = "/tmp/scanstop_report_test_XXXXXX";
  const std::string dir = mkdtemp(pattern);
  const std::string md = writeReport(twoScans(), dir, {"explorer/step_001_evaluation.png"});
  const std::string json = readFile(dir + "/summary.json");
  EXPECT_NE(json.find("\"world\": \"room_10x8\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"scans\": 2"), std::string::npos);
  EXPECT_NE(json.find("\"final_slam_error_m\": 0.0300"), std::string::npos) << json;
  EXPECT_NE(json.find("\"final_odometry_error_m\": 0.5000"), std::string::npos) << json;
  EXPECT_NE(json.find("\"complete\": true"), std::string::npos);
  // The modelled time and its split (twoScans: 80 s scanning, 20 s driving, 3 s compute).
  EXPECT_NE(json.find("\"modelled_time_s\": 103.0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"modelled_scanning_s\": 80.0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"modelled_driving_s\": 20.0"), std::string::npos) << json;
  EXPECT_NE(json.find("\"modelled_compute_s\": 3.0"), std::string::npos) << json;
  for (const char* png : {"/coverage.png", "/trajectory.png", "/pose_error.png"}) {
    const cv::Mat img = cv::imread(dir + png);
    ASSERT_FALSE(img.empty()) << png;
    // Something was drawn besides the white background.
    cv::Mat gray;
    cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
    EXPECT_GT(cv::countNonZero(gray < 128), 100) << png;
  }
  const std::string text = readFile(md);
  EXPECT_NE(text.find("| scans | 2 |"), std::string::npos) << text;
  EXPECT_NE(text.find("(ATE) | RMS 2.1 cm, max 3.0 cm (scan 1)"), std::string::npos) << text;
  EXPECT_NE(text.find("pose_error.png"), std::string::npos) << text;
  EXPECT_NE(readFile(dir + "/trajectory.csv").find("\n1,2.030000,"), std::string::npos);
  EXPECT_NE(text.find("step_001_evaluation.png"), std::string::npos);
  // Without a world (the real robot, or no world_file) there is no true coverage.
  EXPECT_NE(json.find("\"true_coverage\": null"), std::string::npos) << json;
  EXPECT_EQ(text.find("truly reachable"), std::string::npos) << text;
  // In simulation the ground-truth coverage is reported next to the explorer's own figure.
  writeReport(twoScans(), dir, {}, TrueCoverage{0.816, 96.0, 0.9234, 20299, std::nullopt});
  const std::string sim_json = readFile(dir + "/summary.json");
  EXPECT_NE(sim_json.find("\"surface_coverage\": 0.9234"), std::string::npos) << sim_json;
  EXPECT_NE(sim_json.find("\"surface_visible_elements\": 20299"), std::string::npos) << sim_json;
  EXPECT_NE(readFile(dir + "/report.md").find("(of 20299 5 cm elements visible from the reachable floor) | 92.3 % |"),
            std::string::npos)
      << readFile(dir + "/report.md");
  EXPECT_NE(json.find("\"surface_coverage\": null"), std::string::npos) << json;
  EXPECT_NE(sim_json.find("\"true_coverage\": 0.8160"), std::string::npos) << sim_json;
  EXPECT_NE(sim_json.find("\"true_reachable_floor_m2\": 96.00"), std::string::npos) << sim_json;
  EXPECT_NE(
      readFile(dir + "/report.md").find("| coverage of the truly reachable floor (96.0 m2, from the world) | 81.6 % |"),
      std::string::npos)
      << readFile(dir + "/report.md");
  // No mesh measured: null; a mesh measured against the world: its figures in both.
  EXPECT_NE(sim_json.find("\"mesh_distance_median_m\": null"), std::string::npos) << sim_json;
  EXPECT_EQ(readFile(dir + "/report.md").find("the mesh ("), std::string::npos);
  writeReport(twoScans(), dir, {},
              TrueCoverage{0.816, 96.0, 0.9234, 20299, MeshAccuracy{0.0029, 0.0076, 0.0173, 0.923, 3404278}});
  const std::string mesh_json = readFile(dir + "/summary.json");
  EXPECT_NE(mesh_json.find("\"mesh_distance_median_m\": 0.00290"), std::string::npos) << mesh_json;
  EXPECT_NE(mesh_json.find("\"mesh_distance_rms_m\": 0.00760"), std::string::npos) << mesh_json;
  EXPECT_NE(mesh_json.find("\"mesh_distance_p95_m\": 0.01730"), std::string::npos) << mesh_json;
  EXPECT_NE(mesh_json.find("\"mesh_surface_coverage\": 0.9230"), std::string::npos) << mesh_json;
  EXPECT_NE(mesh_json.find("\"mesh_triangles\": 3404278"), std::string::npos) << mesh_json;
  EXPECT_NE(readFile(dir + "/report.md")
                .find("| the mesh (3404278 triangles) against the true surfaces: median / RMS / "
                      "95th percentile distance; the visible surface it covers within 3 cm | "
                      "2.9 / 7.6 / 17.3 mm; 92.3 % |"),
            std::string::npos)
      << readFile(dir + "/report.md");
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

TEST(Report, ScriptPlotsAreLinkedAndTheScriptRun) {
  char pattern[] = "/tmp/scanstop_report_test_XXXXXX";
  const std::string dir = mkdtemp(pattern);
  // make_report.py draws the plots: report.md links report.html and its PNGs, the simple ones are not drawn.
  const std::string text = readFile(writeReport(twoScans(), dir, {}, std::nullopt, true));
  for (const char* name :
       {"(report.html)", "(report_coverage.png)", "(report_trajectory.png)", "(report_pose_error.png)"})
    EXPECT_NE(text.find(name), std::string::npos) << name << "\n" << text;
  EXPECT_TRUE(cv::imread(dir + "/coverage.png").empty());
  // The script runner: success, a failing script (status and log named), a missing one, a hanging one.
  const auto script = [&](const std::string& name, const std::string& body) {
    const std::string path = dir + "/" + name;
    writeFileAtomic(path, "#!/bin/sh\n" + body + "\n");
    EXPECT_EQ(std::system(("chmod +x '" + path + "'").c_str()), 0);
    return path;
  };
  EXPECT_EQ(runReportScript(script("ok.sh", "echo drawn in \"$1\""), dir, 10.0), "");
  EXPECT_NE(readFile(dir + "/make_report.log").find("drawn in " + dir), std::string::npos);
  const std::string failed = runReportScript(script("bad.sh", "echo broken >&2; exit 3"), dir, 10.0);
  EXPECT_NE(failed.find("exited with status 3"), std::string::npos) << failed;
  EXPECT_NE(failed.find(dir + "/make_report.log"), std::string::npos) << failed;
  EXPECT_NE(readFile(dir + "/make_report.log").find("broken"), std::string::npos);
  const std::string missing = runReportScript(dir + "/none.py", dir, 10.0);
  EXPECT_NE(missing.find(dir + "/none.py: not an executable file"), std::string::npos) << missing;
  const std::string hung = runReportScript(script("hang.sh", "exec sleep 30"), dir, 0.3);
  EXPECT_NE(hung.find("took longer than 0.3 s and was killed"), std::string::npos) << hung;
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

TEST(Report, RealRobotHasNoGroundTruthFigures) {
  MissionState st = twoScans();
  for (auto& s : st.scans) s.true_pose.reset();
  const Summary s = summarize(st);
  EXPECT_FALSE(s.has_ground_truth);
  EXPECT_NE(toJson(s).find("\"final_slam_error_m\": null"), std::string::npos);
  EXPECT_EQ(s.ate_scans, 0);
  EXPECT_NE(toJson(s).find("\"ate_rms_m\": null"), std::string::npos);
}

}  // namespace
}  // namespace mission
}  // namespace scanstop
