// Runs the plan_step tool on a map directory written with scanstop_common's MapDirectory.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "scenes.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"

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
  for (const char* key : {"\"success\": true", "\"complete\": false", "\"path\": [{\"x\": 1, \"y\": 1, \"scan\": false}",
                          "\"target\"", "\"score\"", "\"coverage\""})
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
