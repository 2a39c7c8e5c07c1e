// Runs the plan_step tool on a map directory written with scanstop_common's MapDirectory.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/stl_io.h"
#include "scenes.h"

using namespace scanstop;
using namespace scanstop::explorer;

namespace {
struct ToolRun {
  int status = -1;
  std::string out;
};
ToolRun run(const std::string& cmd) {
  ToolRun r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}
std::string tempDir() {
  char tmpl[] = "/tmp/plan_step_test_XXXXXX";
  const char* d = mkdtemp(tmpl);
  if (!d) throw std::runtime_error("mkdtemp failed");
  return d;
}
}  // namespace

TEST(PlanStep, PlansOnAMapDirectoryAndPrintsJson) {
  const std::string dir = tempDir();
  const test::Scene s = test::twoRooms();
  {
    MapDirectory md(dir + "/map");
    const Pose2D pose(1.0, 1.0, 0.5);
    MapScanInfo info;
    info.index = 0;
    info.map_pose = pose;
    PointCloud cloud;
    const Eigen::Isometry3f T_base_map = pose.toIsometry3f().inverse();
    for (const auto& p : test::simulateScan(s, {pose.x, pose.y}, 3.0)) cloud.push_back(T_base_map * p);
    md.append(info, cloud);
  }
  const ToolRun r = run(std::string(PLAN_STEP_EXE) + " " + dir + "/map " + dir + "/out --json --pose 1.0,1.0,0.0");
  ASSERT_EQ(r.status, 0) << r.out;
  for (const char* key : {"\"success\": true", "\"complete\": false",
                          "\"path\": [{\"x\": 1, \"y\": 1, \"scan\": false, \"clearance_m\": ", "\"target\"",
                          "\"score\"", "\"coverage\""})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " missing in " << r.out;
  for (const char* img : {"floor", "distance", "cost", "knowledge", "evaluation"})
    EXPECT_FALSE(cv::imread(dir + "/out/" + img + ".png").empty()) << img;
  EXPECT_EQ(readFile(dir + "/out/path.csv").substr(0, 9), "x,y,scan\n");
  EXPECT_NE(readFile(dir + "/out/plan.json").find("\"path\""), std::string::npos);

  const ToolRun missing = run(std::string(PLAN_STEP_EXE) + " " + dir + "/nothing " + dir + "/out");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.out.find("no such map directory"), std::string::npos) << missing.out;
  const ToolRun bad_pose = run(std::string(PLAN_STEP_EXE) + " " + dir + "/map " + dir + "/out --pose 1,x");
  EXPECT_EQ(bad_pose.status, 2) << bad_pose.out;
  const ToolRun usage = run(std::string(PLAN_STEP_EXE));
  EXPECT_EQ(usage.status, 2);
  EXPECT_NE(usage.out.find("usage"), std::string::npos);
  std::system(("rm -rf " + dir).c_str());
}

namespace {
/// A map directory of simulated scans of the two-room scene at the given poses.
std::string makeMap(const std::string& dir, const std::vector<Pose2D>& poses) {
  const test::Scene s = test::twoRooms();
  MapDirectory md(dir);
  for (size_t i = 0; i < poses.size(); ++i) {
    MapScanInfo info;
    info.index = static_cast<uint32_t>(i);
    info.map_pose = poses[i];
    info.odom_pose = poses[i];
    PointCloud cloud;
    const Eigen::Isometry3f T_base_map = poses[i].toIsometry3f().inverse();
    for (const auto& p : test::simulateScan(s, {poses[i].x, poses[i].y}, 3.0)) cloud.push_back(T_base_map * p);
    md.append(info, cloud);
  }
  return dir;
}
/// Replaces the first occurrence of `from` in a file.
void edit(const std::string& path, const std::string& from, const std::string& to) {
  std::string text = readFile(path);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << text;
  writeFileAtomic(path, text.replace(at, from.size(), to));
}
bool exists(const std::string& path) {
  return std::ifstream(path).good() || std::system(("test -e " + path).c_str()) == 0;
}
}  // namespace

namespace {
/// The longest leg of OUT_DIR/path.csv ("x,y,scan" lines) [m].
double longestLeg(const std::string& csv_path) {
  std::istringstream in(readFile(csv_path));
  std::string line;
  std::getline(in, line);  // header
  double longest = 0.0, px = 0.0, py = 0.0;
  bool first = true;
  while (std::getline(in, line)) {
    double x = 0.0, y = 0.0;
    if (std::sscanf(line.c_str(), "%lf,%lf", &x, &y) != 2) continue;
    if (!first) longest = std::max(longest, std::hypot(x - px, y - py));
    first = false;
    px = x;
    py = y;
  }
  return longest;
}
}  // namespace

// Issue #21: plan_step --config reads an explorer parameter file (config/explorer.yaml) as
// explorer_node reads its parameters; a bad file is refused naming the parameter.
TEST(PlanStep, ConfigFileSetsTheExplorersParameters) {
  const std::string dir = tempDir();
  makeMap(dir + "/map", {Pose2D(1.0, 1.0, 0.0)});
  const std::string exe = std::string(PLAN_STEP_EXE) + " " + dir + "/map " + dir + "/out --pose 1.0,1.0,0.0";
  const ToolRun plain = run(exe);
  ASSERT_EQ(plain.status, 0) << plain.out;
  const double plain_leg = longestLeg(dir + "/out/path.csv");
  ASSERT_GT(plain_leg, 0.8) << "the scene needs a long first path for this test";
  writeFileAtomic(dir + "/short.yaml", "d_max_m: 0.6\n");
  const ToolRun short_legs = run(exe + " --config " + dir + "/short.yaml");
  ASSERT_EQ(short_legs.status, 0) << short_legs.out;
  EXPECT_LE(longestLeg(dir + "/out/path.csv"), 0.6 + 1e-6);
  const ToolRun mission = run(exe + " --config " + std::string(SCANSTOP_CONFIG_DIR) + "/explorer.yaml");
  EXPECT_EQ(mission.status, 0) << mission.out;
  writeFileAtomic(dir + "/bad.yaml", "d_max_m: 0.6\nk_r: 2.0\n");
  const ToolRun bad = run(exe + " --config " + dir + "/bad.yaml");
  EXPECT_EQ(bad.status, 2) << bad.out;
  EXPECT_NE(bad.out.find("bad.yaml: unknown explorer parameter 'k_r'"), std::string::npos) << bad.out;
  const ToolRun missing = run(exe + " --config " + dir + "/none.yaml");
  EXPECT_EQ(missing.status, 2) << missing.out;
  EXPECT_NE(missing.out.find("none.yaml: no such file (the parameter file)"), std::string::npos) << missing.out;
  std::system(("rm -rf " + dir).c_str());
}

// Issue #22 class 2: plan_step on a map with a missing scan file or a NaN pose went on with the rest
// and exited 0 (the plan changed). It refuses the map naming the file and line, or warns for each
// skipped item with --skip-bad.
TEST(PlanStep, RefusesAMapWithAMissingScanOrANaNPoseNamingItUnlessSkipBad) {
  const std::string dir = tempDir();
  const std::string map = makeMap(dir + "/map", {Pose2D(1.0, 1.0, 0.0), Pose2D(1.5, 1.0, 0.0)});
  ASSERT_EQ(std::remove((map + "/scans/scan_0001.pcd").c_str()), 0);
  ToolRun r = run(std::string(PLAN_STEP_EXE) + " " + map + " " + dir + "/out");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find(map + "/scans/scan_0001.pcd: no such file (1 problem in the map; --skip-bad loads the rest)"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(exists(dir + "/out")) << "nothing written for a refused map";
  r = run(std::string(PLAN_STEP_EXE) + " " + map + " " + dir + "/out --skip-bad");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("plan_step: warning: skipped: " + map + "/scans/scan_0001.pcd: no such file; scan 1 skipped"),
            std::string::npos)
      << r.out;

  const std::string map2 = makeMap(dir + "/map2", {Pose2D(1.0, 1.0, 0.0), Pose2D(1.5, 1.0, 0.0)});
  edit(map2 + "/poses.csv", "\n1,scans/scan_0001.pcd,0,1.5,", "\n1,scans/scan_0001.pcd,0,nan,");
  // poses.csv alone: the scan ledger's journal would restore the line (and name that instead).
  ASSERT_EQ(std::remove((map2 + "/poses_journal.csv").c_str()), 0);
  r = run(std::string(PLAN_STEP_EXE) + " " + map2 + " " + dir + "/out2");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find(map2 + "/poses.csv: line 3: column 4 ('nan') is not a finite number (1 problem"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(std::system(("rm -rf " + dir).c_str()), 0);
}

// Issue #22 class 3: one pose 100 km away grew plan_step to 6 GB over 57 s before OpenCV failed to
// allocate. The pose is refused when poses.csv is read; a pose within the 10 km limit but far from the
// others is refused by the grid's cell limit, both before any large allocation.
TEST(PlanStep, RefusesAFarPoseBeforeAllocatingAnything) {
  const std::string dir = tempDir();
  const std::string map = makeMap(dir + "/map", {Pose2D(1.0, 1.0, 0.0), Pose2D(1.5, 1.0, 0.0)});
  edit(map + "/poses.csv", "\n1,scans/scan_0001.pcd,0,1.5,1,", "\n1,scans/scan_0001.pcd,0,100000,1,");
  ToolRun r = run(std::string(PLAN_STEP_EXE) + " " + map + " " + dir + "/out");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find(map + "/poses.csv: line 3: map pose (columns 4-6) (x=100000 m, y=1 m, yaw=0 rad) is beyond the "
                             "10000 m pose limit"),
            std::string::npos)
      << r.out;
  const std::string map2 = makeMap(dir + "/map2", {Pose2D(1.0, 1.0, 0.0), Pose2D(9000.0, 9000.0, 0.0)});
  r = run(std::string(PLAN_STEP_EXE) + " " + map2 + " " + dir + "/out2");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("more than the limit of 10000000 cells"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(dir + "/out2"));
  r = run(std::string(PLAN_STEP_EXE) + " " + dir + "/map " + dir + "/out3 --pose 20000,0,0");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("--pose 20000,0,0: value 1 ('20000') is not a number in [-10000, 10000]"), std::string::npos)
      << r.out;
  EXPECT_EQ(std::system(("rm -rf " + dir).c_str()), 0);
}

// Issue #22 class 7: strict options; --help before anything is created; unknown options named.
TEST(PlanStep, StrictOptionsAndHelp) {
  const std::string dir = tempDir();
  const std::string map = makeMap(dir + "/map", {Pose2D(1.0, 1.0, 0.0)});
  const std::string base = std::string(PLAN_STEP_EXE) + " " + map + " " + dir + "/out";
  ToolRun r = run(base + " --scale 99999999999");  // std::atoi wrapped this around before
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("plan_step: --scale 99999999999: not an integer in [1, 16]"), std::string::npos) << r.out;
  r = run(base + " --scale 2x");  // read as 2 before
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--scale 2x: not an integer in [1, 16]"), std::string::npos) << r.out;
  r = run(base + " --pose nan,0,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--pose nan,0,0: value 1 ('nan')"), std::string::npos) << r.out;
  r = run(base + " --bogus");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("plan_step: unknown option --bogus"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(dir + "/out"));
  r = run(std::string(PLAN_STEP_EXE) + " " + dir + "/new_map " + dir + "/out --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: plan_step", 0), 0u) << r.out;
  EXPECT_FALSE(exists(dir + "/out"));
  EXPECT_FALSE(exists(dir + "/new_map"));
  r = run(base + " --json --scale 1");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;
  EXPECT_EQ(std::system(("rm -rf " + dir).c_str()), 0);
}
