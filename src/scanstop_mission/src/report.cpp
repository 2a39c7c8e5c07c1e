#include "scanstop_mission/report.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <thread>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_eval/truth_file.h"

namespace scanstop {
namespace mission {
namespace {

std::string num(double v, int precision = 4) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream out;
  out << std::setprecision(precision) << std::fixed << v;
  return out.str();
}

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

double yawErrorDeg(const Pose2D& a, const Pose2D& b) { return std::abs(normalizeAngle(a.yaw - b.yaw)) * 180.0 / M_PI; }

void writePng(const std::string& path, const cv::Mat& image) {
  std::vector<uchar> buffer;
  if (!cv::imencode(".png", image, buffer)) throw IoError(path, "PNG encoding failed");
  writeFileAtomic(path, std::string(buffer.begin(), buffer.end()));
}

/// A simple chart canvas mapping data coordinates to pixels with a margin for labels.
struct Canvas {
  cv::Mat img;
  double x0, x1, y0, y1;
  int margin = 60;
  Canvas(int w, int h, double xa, double xb, double ya, double yb, bool equal_aspect)
      : img(h, w, CV_8UC3, cv::Scalar(255, 255, 255)), x0(xa), x1(xb), y0(ya), y1(yb) {
    if (x1 - x0 < 1e-9) x1 = x0 + 1.0;
    if (y1 - y0 < 1e-9) y1 = y0 + 1.0;
    if (equal_aspect) {
      const double sx = (w - 2.0 * margin) / (x1 - x0), sy = (h - 2.0 * margin) / (y1 - y0);
      const double s = std::min(sx, sy);
      const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
      const double hw = 0.5 * (w - 2.0 * margin) / s, hh = 0.5 * (h - 2.0 * margin) / s;
      x0 = cx - hw;
      x1 = cx + hw;
      y0 = cy - hh;
      y1 = cy + hh;
    }
  }
  cv::Point px(double x, double y) const {
    return cv::Point(static_cast<int>(margin + (x - x0) / (x1 - x0) * (img.cols - 2 * margin)),
                     static_cast<int>(img.rows - margin - (y - y0) / (y1 - y0) * (img.rows - 2 * margin)));
  }
  void text(const std::string& s, cv::Point p, double scale = 0.5, cv::Scalar color = cv::Scalar(0, 0, 0)) {
    cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, color, 1, cv::LINE_AA);
  }
  void axes(const std::string& xlabel, const std::string& ylabel, const std::string& title) {
    cv::rectangle(img, px(x0, y0), px(x1, y1), cv::Scalar(0, 0, 0), 1);
    for (int i = 0; i <= 4; ++i) {
      const double xv = x0 + (x1 - x0) * i / 4.0, yv = y0 + (y1 - y0) * i / 4.0;
      text(num(xv, 1), px(xv, y0) + cv::Point(-12, 20), 0.4);
      text(num(yv, 2), px(x0, yv) + cv::Point(-55, 4), 0.4);
    }
    text(xlabel, cv::Point(img.cols / 2 - 40, img.rows - 12));
    text(ylabel, cv::Point(5, margin - 20));
    text(title, cv::Point(margin, 25), 0.6);
  }
};

}  // namespace

Summary summarize(const MissionState& st) {
  Summary s;
  s.world = st.world;
  s.state = toString(st.state);
  s.scans = static_cast<int>(st.scans.size());
  s.coverage = st.coverage;
  s.collisions = st.collisions;
  s.complete = st.complete;
  s.complete_reason = st.complete_reason;
  s.elapsed_s = st.elapsed_s;
  s.modelled_time_s = st.modelled_time_s;
  s.modelled_scan_s = st.modelled_scan_s;
  s.modelled_drive_s = st.modelled_drive_s;
  s.modelled_compute_s = st.modelled_compute_s;
  double compute_sum = 0.0, scan_sum = 0.0;
  for (const ScanRecord& r : st.scans) {
    const double c = r.register_wall_s + r.plan_wall_s;
    compute_sum += c;
    s.compute_per_cycle_max_s = std::max(s.compute_per_cycle_max_s, c);
    scan_sum += r.scan_time_s;
    if (!r.converged) ++s.unconverged_registrations;
  }
  s.has_clearance = st.clearance_motions > 0 && st.min_clearance_m >= 0.0;
  s.min_clearance_m = st.min_clearance_m;
  s.clearance_legs = st.clearance_legs;
  s.close_legs = st.close_legs;
  // The pose error of every scan (ATE) and odometry's: scanstop_eval's, as icp_replay's.
  std::vector<Pose2D> slam_poses, odom_poses;
  std::vector<std::optional<Pose2D>> truth;
  for (const ScanRecord& r : st.scans) {
    slam_poses.push_back(r.map_pose);
    odom_poses.push_back(r.odom_pose);
    truth.push_back(r.true_pose);
  }
  const eval::TrajectoryError slam_error = eval::trajectoryError(slam_poses, truth);
  const eval::TrajectoryError odom_error = eval::trajectoryError(odom_poses, truth);
  s.ate_scans = slam_error.scans;
  if (s.ate_scans > 0) {
    s.ate_rms_m = slam_error.rms_m;
    s.ate_max_m = slam_error.max_m;
    s.ate_max_scan = st.scans[slam_error.max_at].index;
    s.ate_yaw_rms_deg = slam_error.yaw_rms_deg;
    s.ate_yaw_max_deg = slam_error.yaw_max_deg;
    s.odom_ate_rms_m = odom_error.rms_m;
    s.odom_ate_max_m = odom_error.max_m;
  }
  if (!st.scans.empty()) {
    s.compute_per_cycle_mean_s = compute_sum / st.scans.size();
    s.scan_time_mean_s = scan_sum / st.scans.size();
    const ScanRecord& last = st.scans.back();
    if (last.true_pose) {
      s.has_ground_truth = true;
      s.slam_error_m = std::hypot(last.map_pose.x - last.true_pose->x, last.map_pose.y - last.true_pose->y);
      s.slam_error_yaw_deg = yawErrorDeg(last.map_pose, *last.true_pose);
      // The odometry frame starts at the start pose, as the map frame does.
      s.odom_error_m = std::hypot(last.odom_pose.x - last.true_pose->x, last.odom_pose.y - last.true_pose->y);
      s.odom_error_yaw_deg = yawErrorDeg(last.odom_pose, *last.true_pose);
    }
  }
  return s;
}

std::string toJson(const Summary& s) {
  std::ostringstream out;
  out << "{\n"
      << "  \"world\": " << quote(s.world) << ",\n"
      << "  \"state\": " << quote(s.state) << ",\n"
      << "  \"scans\": " << s.scans << ",\n"
      << "  \"coverage\": " << num(s.coverage) << ",\n"
      << "  \"true_coverage\": " << (s.has_true_coverage ? num(s.true_coverage) : "null") << ",\n"
      << "  \"true_reachable_floor_m2\": " << (s.has_true_coverage ? num(s.true_reachable_m2, 2) : "null") << ",\n"
      << "  \"surface_coverage\": " << (s.has_surface_coverage ? num(s.surface_coverage) : "null") << ",\n"
      << "  \"surface_visible_elements\": " << (s.has_surface_coverage ? std::to_string(s.surface_visible) : "null")
      << ",\n"
      << "  \"mesh_triangles\": " << (s.has_mesh_accuracy ? std::to_string(s.mesh.triangles) : "null") << ",\n"
      << "  \"mesh_distance_median_m\": " << (s.has_mesh_accuracy ? num(s.mesh.median_m, 5) : "null") << ",\n"
      << "  \"mesh_distance_rms_m\": " << (s.has_mesh_accuracy ? num(s.mesh.rms_m, 5) : "null") << ",\n"
      << "  \"mesh_distance_p95_m\": " << (s.has_mesh_accuracy ? num(s.mesh.p95_m, 5) : "null") << ",\n"
      << "  \"mesh_surface_coverage\": " << (s.has_mesh_accuracy ? num(s.mesh.surface_coverage) : "null") << ",\n"
      << "  \"collisions\": " << s.collisions << ",\n"
      << "  \"min_clearance_m\": " << (s.has_clearance ? num(s.min_clearance_m) : "null") << ",\n"
      << "  \"legs_measured\": " << (s.has_clearance ? std::to_string(s.clearance_legs) : "null") << ",\n"
      << "  \"legs_closer_than_5cm\": " << (s.has_clearance ? std::to_string(s.close_legs) : "null") << ",\n"
      << "  \"complete\": " << (s.complete ? "true" : "false") << ",\n"
      << "  \"complete_reason\": " << quote(s.complete_reason) << ",\n"
      << "  \"ground_truth\": " << (s.has_ground_truth ? "true" : "false") << ",\n"
      << "  \"final_slam_error_m\": " << (s.has_ground_truth ? num(s.slam_error_m) : "null") << ",\n"
      << "  \"final_slam_error_yaw_deg\": " << (s.has_ground_truth ? num(s.slam_error_yaw_deg) : "null") << ",\n"
      << "  \"final_odometry_error_m\": " << (s.has_ground_truth ? num(s.odom_error_m) : "null") << ",\n"
      << "  \"final_odometry_error_yaw_deg\": " << (s.has_ground_truth ? num(s.odom_error_yaw_deg) : "null") << ",\n"
      << "  \"ate_scans\": " << s.ate_scans << ",\n"
      << "  \"ate_rms_m\": " << (s.ate_scans > 0 ? num(s.ate_rms_m) : "null") << ",\n"
      << "  \"ate_max_m\": " << (s.ate_scans > 0 ? num(s.ate_max_m) : "null") << ",\n"
      << "  \"ate_max_scan\": " << (s.ate_scans > 0 ? std::to_string(s.ate_max_scan) : "null") << ",\n"
      << "  \"ate_yaw_rms_deg\": " << (s.ate_scans > 0 ? num(s.ate_yaw_rms_deg) : "null") << ",\n"
      << "  \"ate_yaw_max_deg\": " << (s.ate_scans > 0 ? num(s.ate_yaw_max_deg) : "null") << ",\n"
      << "  \"odometry_ate_rms_m\": " << (s.ate_scans > 0 ? num(s.odom_ate_rms_m) : "null") << ",\n"
      << "  \"odometry_ate_max_m\": " << (s.ate_scans > 0 ? num(s.odom_ate_max_m) : "null") << ",\n"
      << "  \"unconverged_registrations\": " << s.unconverged_registrations << ",\n"
      << "  \"compute_per_cycle_mean_s\": " << num(s.compute_per_cycle_mean_s) << ",\n"
      << "  \"compute_per_cycle_max_s\": " << num(s.compute_per_cycle_max_s) << ",\n"
      << "  \"scan_time_mean_s\": " << num(s.scan_time_mean_s) << ",\n"
      << "  \"modelled_time_s\": " << num(s.modelled_time_s, 1) << ",\n"
      << "  \"modelled_scanning_s\": " << num(s.modelled_scan_s, 1) << ",\n"
      << "  \"modelled_driving_s\": " << num(s.modelled_drive_s, 1) << ",\n"
      << "  \"modelled_compute_s\": " << num(s.modelled_compute_s, 1) << ",\n"
      << "  \"elapsed_s\": " << num(s.elapsed_s, 1) << "\n"
      << "}\n";
  return out.str();
}

std::string trajectoryCsv(const MissionState& st) {
  std::ostringstream out;
  out << "index,x,y,yaw,registered_x,registered_y,registered_yaw,odom_x,odom_y,odom_yaw,true_x,true_y,true_yaw,"
         "error_m,error_yaw_deg,odom_error_m\n";
  const auto pose = [&out](const std::optional<Pose2D>& p) {
    if (p)
      out << num(p->x, 6) << "," << num(p->y, 6) << "," << num(p->yaw, 6);
    else
      out << ",,";
  };
  for (const ScanRecord& r : st.scans) {
    out << r.index << ",";
    pose(r.map_pose);
    out << ",";
    pose(r.registered_pose.value_or(r.map_pose));
    out << ",";
    pose(r.odom_pose);
    out << ",";
    pose(r.true_pose);
    out << ",";
    if (r.true_pose)
      out << num(std::hypot(r.map_pose.x - r.true_pose->x, r.map_pose.y - r.true_pose->y), 6) << ","
          << num(yawErrorDeg(r.map_pose, *r.true_pose), 4) << ","
          << num(std::hypot(r.odom_pose.x - r.true_pose->x, r.odom_pose.y - r.true_pose->y), 6);
    else
      out << ",,";
    out << "\n";
  }
  return out.str();
}

std::string writeReport(const MissionState& st, const std::string& run_dir, const std::vector<std::string>& images,
                        const std::optional<TrueCoverage>& truth, bool script_plots) {
  Summary s = summarize(st);
  if (truth) {
    s.has_true_coverage = true;
    s.true_coverage = truth->coverage;
    s.true_reachable_m2 = truth->reachable_m2;
    s.has_surface_coverage = truth->surface_coverage.has_value();
    s.surface_coverage = truth->surface_coverage.value_or(0.0);
    s.surface_visible = truth->surface_visible;
    s.has_mesh_accuracy = truth->mesh.has_value();
    if (truth->mesh) s.mesh = *truth->mesh;
  }
  writeFileAtomic(run_dir + "/summary.json", toJson(s));
  writeFileAtomic(run_dir + "/trajectory.csv", trajectoryCsv(st));

  // The plots: make_report.py draws them after this (script_plots), else these simple ones.
  const std::string coverage_png = script_plots ? "report_coverage.png" : "coverage.png";
  const std::string trajectory_png = script_plots ? "report_trajectory.png" : "trajectory.png";
  const std::string error_png = script_plots ? "report_pose_error.png" : "pose_error.png";
  // Coverage against scan count.
  if (!script_plots) {
    Canvas c(640, 400, 0.0, std::max<double>(1.0, st.scans.size()), 0.0, 1.0, false);
    c.axes("scans", "coverage", "Observed share of the reachable floor");
    cv::Point prev = c.px(0, 0);
    for (size_t i = 0; i < st.scans.size(); ++i) {
      const cv::Point p = c.px(i + 1.0, st.scans[i].coverage);
      cv::line(c.img, prev, p, cv::Scalar(200, 80, 0), 2, cv::LINE_AA);
      cv::circle(c.img, p, 3, cv::Scalar(200, 80, 0), cv::FILLED);
      prev = p;
    }
    writePng(run_dir + "/coverage.png", c.img);
  }

  // Trajectories: SLAM, odometry and (simulation) ground truth, at the scan poses.
  if (!script_plots) {
    double xa = 1e9, xb = -1e9, ya = 1e9, yb = -1e9;
    const auto grow = [&](const Pose2D& p) {
      xa = std::min(xa, p.x);
      xb = std::max(xb, p.x);
      ya = std::min(ya, p.y);
      yb = std::max(yb, p.y);
    };
    for (const ScanRecord& r : st.scans) {
      grow(r.map_pose);
      grow(r.odom_pose);
      if (r.true_pose) grow(*r.true_pose);
    }
    if (st.scans.empty()) xa = xb = ya = yb = 0.0;
    Canvas c(800, 700, xa - 0.5, xb + 0.5, ya - 0.5, yb + 0.5, true);
    c.axes("x [m]", "y [m]", "Scan poses: SLAM (blue), odometry (red), ground truth (green)");
    const auto draw = [&](auto pose_of, cv::Scalar color) {
      for (size_t i = 0; i < st.scans.size(); ++i) {
        const std::optional<Pose2D> p = pose_of(st.scans[i]);
        if (!p) continue;
        const cv::Point q = c.px(p->x, p->y);
        cv::circle(c.img, q, 4, color, cv::FILLED, cv::LINE_AA);
        const cv::Point h = c.px(p->x + 0.25 * std::cos(p->yaw), p->y + 0.25 * std::sin(p->yaw));
        cv::line(c.img, q, h, color, 1, cv::LINE_AA);
        if (i > 0) {
          const std::optional<Pose2D> o = pose_of(st.scans[i - 1]);
          if (o) cv::line(c.img, c.px(o->x, o->y), q, color, 1, cv::LINE_AA);
        }
      }
    };
    draw([](const ScanRecord& r) { return std::optional<Pose2D>(r.odom_pose); }, cv::Scalar(40, 40, 220));
    draw([](const ScanRecord& r) { return r.true_pose; }, cv::Scalar(40, 170, 40));
    draw([](const ScanRecord& r) { return std::optional<Pose2D>(r.map_pose); }, cv::Scalar(200, 80, 0));
    writePng(run_dir + "/trajectory.png", c.img);
  }

  // Position error of every scan against ground truth (simulation): SLAM and odometry alone.
  if (s.ate_scans > 0 && !script_plots) {
    double top = 0.01;
    for (const ScanRecord& r : st.scans)
      if (r.true_pose)
        top = std::max({top, std::hypot(r.map_pose.x - r.true_pose->x, r.map_pose.y - r.true_pose->y) * 100.0,
                        std::min(std::hypot(r.odom_pose.x - r.true_pose->x, r.odom_pose.y - r.true_pose->y) * 100.0,
                                 4.0 * std::max(1.0, s.ate_max_m * 100.0))});
    Canvas c(640, 400, 0.0, std::max<double>(1.0, st.scans.size()), 0.0, top * 1.05, false);
    c.axes("scan", "error [cm]", "Position error per scan: SLAM (blue), odometry (red)");
    const auto draw = [&](bool slam, cv::Scalar color) {
      std::optional<cv::Point> prev;
      for (size_t i = 0; i < st.scans.size(); ++i) {
        const ScanRecord& r = st.scans[i];
        if (!r.true_pose) {
          prev.reset();
          continue;
        }
        const Pose2D& p = slam ? r.map_pose : r.odom_pose;
        const double e = std::min(std::hypot(p.x - r.true_pose->x, p.y - r.true_pose->y) * 100.0, top * 1.05);
        const cv::Point q = c.px(i + 1.0, e);
        if (prev) cv::line(c.img, *prev, q, color, 2, cv::LINE_AA);
        cv::circle(c.img, q, 3, color, cv::FILLED);
        prev = q;
      }
    };
    draw(false, cv::Scalar(40, 40, 220));
    draw(true, cv::Scalar(200, 80, 0));
    writePng(run_dir + "/pose_error.png", c.img);
  }

  std::ostringstream md;
  md << "# Exploration report" << (s.world.empty() ? "" : ": " + s.world) << "\n\n"
     << (script_plots ? "One page with every plot: [report.html](report.html) (drawn by `make_report.py`).\n\n" : "")
     << "| figure | value |\n|---|---|\n"
     << "| final state | " << s.state << " |\n"
     << "| exploration complete | " << (s.complete ? "yes" : "no") << " (" << s.complete_reason << ") |\n"
     << "| scans | " << s.scans << " |\n"
     << "| coverage of the reachable floor (explorer's map) | " << num(s.coverage * 100.0, 1) << " % |\n";
  if (s.has_true_coverage)
    md << "| coverage of the truly reachable floor (" << num(s.true_reachable_m2, 1) << " m2, from the world) | "
       << num(s.true_coverage * 100.0, 1) << " % |\n";
  if (s.has_surface_coverage)
    md << "| surface held by the map within 3 cm (of " << s.surface_visible
       << " 5 cm elements visible from the reachable floor) | " << num(s.surface_coverage * 100.0, 1) << " % |\n";
  if (s.has_mesh_accuracy)
    md << "| the mesh (" << s.mesh.triangles << " triangles) against the true surfaces: median / RMS / 95th percentile "
       << "distance; the visible surface it covers within 3 cm | " << num(s.mesh.median_m * 1000.0, 1) << " / "
       << num(s.mesh.rms_m * 1000.0, 1) << " / " << num(s.mesh.p95_m * 1000.0, 1) << " mm; "
       << num(s.mesh.surface_coverage * 100.0, 1) << " % |\n";
  md << "| collisions | " << s.collisions << " |\n"
     << (s.has_clearance ? "| smallest true clearance of the body (all motions) | " +
                               num(s.min_clearance_m * 100.0, 1) + " cm; " + std::to_string(s.close_legs) + " of " +
                               std::to_string(s.clearance_legs) + " straight legs closer than 5 cm |\n"
                         : std::string())
     << "| registrations that did not converge | " << s.unconverged_registrations << " |\n";
  if (s.ate_scans > 0)
    md << "| SLAM pose error over all " << s.ate_scans << " scans (ATE) | RMS " << num(s.ate_rms_m * 100.0, 1)
       << " cm, max " << num(s.ate_max_m * 100.0, 1) << " cm (scan " << s.ate_max_scan << "); yaw RMS "
       << num(s.ate_yaw_rms_deg, 2) << " deg, max " << num(s.ate_yaw_max_deg, 2) << " deg |\n"
       << "| odometry-only error over all scans | RMS " << num(s.odom_ate_rms_m * 100.0, 1) << " cm, max "
       << num(s.odom_ate_max_m * 100.0, 1) << " cm |\n";
  if (s.has_ground_truth) {
    md << "| final SLAM pose error | " << num(s.slam_error_m * 100.0, 1) << " cm, " << num(s.slam_error_yaw_deg, 2)
       << " deg |\n"
       << "| final odometry-only error | " << num(s.odom_error_m * 100.0, 1) << " cm, " << num(s.odom_error_yaw_deg, 2)
       << " deg |\n";
  }
  md << "| compute per cycle (register + plan) | mean " << num(s.compute_per_cycle_mean_s, 2) << " s, max "
     << num(s.compute_per_cycle_max_s, 2) << " s |\n"
     << "| modelled scan time | " << num(s.scan_time_mean_s, 1) << " s per scan |\n"
     << "| modelled mission time | " << num(s.modelled_time_s / 60.0, 1) << " min: scanning "
     << num(s.modelled_scan_s / 60.0, 1) << " min, driving " << num(s.modelled_drive_s / 60.0, 1) << " min, compute "
     << num(s.modelled_compute_s / 60.0, 1) << " min |\n"
     << "| wall time | " << num(s.elapsed_s, 1) << " s |\n\n"
     << "## Coverage\n\n![coverage](" << coverage_png << ")\n\n"
     << "## Trajectory\n\n![trajectory](" << trajectory_png << ")\n\n";
  if (s.ate_scans > 0)
    md << "## Pose error per scan\n\n![pose error](" << error_png << ")\n\nPer-scan figures: `trajectory.csv`.\n\n";
  if (!images.empty()) {
    md << "## Explorer, step by step\n\n";
    for (const std::string& image : images) md << "![" << image << "](" << image << ")\n\n";
  }
  md << "## Events\n\n";
  for (const EventRecord& e : st.events) md << "- " << num(e.elapsed_s, 1) << " s: " << e.what << "\n";
  md << "\nMachine-readable: `summary.json`. Map: `map/`. Mission state: `mission_state.yaml`.\n";
  const std::string path = run_dir + "/report.md";
  writeFileAtomic(path, md.str());
  return path;
}

std::string runReportScript(const std::string& script, const std::string& run_dir, double timeout_s) {
  if (::access(script.c_str(), X_OK) != 0) return script + ": not an executable file";
  const std::string log = run_dir + "/make_report.log";
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return log + ": cannot open for writing";
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd);
    return "cannot fork to run " + script;
  }
  if (pid == 0) {  // the child: only async-signal-safe calls until exec
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    const int null_in = ::open("/dev/null", O_RDONLY);
    if (null_in >= 0) ::dup2(null_in, STDIN_FILENO);
    char* const argv[] = {const_cast<char*>(script.c_str()), const_cast<char*>(run_dir.c_str()), nullptr};
    ::execv(script.c_str(), argv);
    ::_exit(127);
  }
  ::close(fd);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (true) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0) return "lost " + script + " (waitpid failed)";
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      std::ostringstream out;
      out << script << " took longer than " << timeout_s << " s and was killed (output in " << log << ")";
      return out.str();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  std::ostringstream out;
  out << script << " ";
  if (WIFEXITED(status))
    out << "exited with status " << WEXITSTATUS(status);
  else
    out << "ended by signal " << WTERMSIG(status);
  out << " (output in " << log << ")";
  return out.str();
}

}  // namespace mission
}  // namespace scanstop
