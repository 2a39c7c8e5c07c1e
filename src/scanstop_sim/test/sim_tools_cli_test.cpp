// scan_world and make_worlds on bad arguments (issue #22 class 7 and 6): the one option parser
// (strict numbers, --help before anything else, unknown options named) and outputs named before work.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "scanstop_common/cli_test.h"

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& cmd) { return scanstop::test_util::runCommand(cmd); }

bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

const std::string kScanWorld = SCAN_WORLD_EXE;
const std::string kMakeWorlds = MAKE_WORLDS_EXE;
const std::string kWorld = std::string(SCANSTOP_WORLDS_DIR) + "/room_10x8.stl";

}  // namespace

TEST(ScanWorldCli, BadArgumentsAreNamedAndNothingIsWritten) {
  TempDir tmp("sim_tools_cli_test");
  const std::string base = kScanWorld + " " + kWorld + " " + tmp.path + "/scan.pcd";
  CliRun r = run(base + " --pose 1,1,0 --planes 37");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("scan_world: --planes 37: must be one of 50, 100, 200, 400"), std::string::npos) << r.out;
  r = run(base + " --pose 1,1,0 --seed 7x");  // std::atol read 7 before
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--seed 7x: not an integer in [0, 9223372036854775807]"), std::string::npos) << r.out;
  r = run(base + " --pose 1,nan,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--pose 1,nan,0: value 2 ('nan')"), std::string::npos) << r.out;
  r = run(base + " --pose 1,1,0 --profile noisy");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--profile noisy: must be one of perfect, thesis"), std::string::npos) << r.out;
  r = run(base);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--pose is required"), std::string::npos) << r.out;
  r = run(base + " --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: scan_world", 0), 0u) << r.out;
  EXPECT_FALSE(exists(tmp.path + "/scan.pcd"));
  r = run(kScanWorld + " " + kWorld + " " + tmp.path + "/no_dir/scan.pcd --pose 1,1,0 --planes 50");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(
      r.out.find(tmp.path + "/no_dir/scan.pcd: cannot write: the directory " + tmp.path + "/no_dir does not exist"),
      std::string::npos)
      << r.out;
}

// --mixed-pixels turns on the scanner's mixed pixels at depth steps (the bench of the fused map
// scans artifacts_room with them); the world's materials come from the YAML next to the STL.
TEST(ScanWorldCli, MixedPixelsAreCountedWhenAskedFor) {
  TempDir tmp("sim_tools_cli_test");
  const std::string base = kScanWorld + " " + std::string(SCANSTOP_WORLDS_DIR) + "/artifacts_room.stl " + tmp.path +
                           "/scan.pcd --pose 1.5,1.5,0 --planes 50";
  CliRun r = run(base + " --mixed-pixels");
  ASSERT_EQ(r.status, 0) << r.out;
  const size_t at = r.out.find(" mixed pixels");
  ASSERT_NE(at, std::string::npos) << r.out;
  const size_t from = r.out.rfind(", ", at);
  ASSERT_NE(from, std::string::npos) << r.out;
  EXPECT_GT(std::stoul(r.out.substr(from + 2, at - from - 2)), 10u) << r.out;  // at the room's depth steps
  EXPECT_TRUE(exists(tmp.path + "/scan.pcd"));
  r = run(base);
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("mixed pixels"), std::string::npos) << r.out;
}

TEST(MakeWorldsCli, BadSeedsAndMissingDirectoriesAreNamed) {
  TempDir tmp("sim_tools_cli_test");
  CliRun r = run(kMakeWorlds + " " + tmp.path + " --furnished 1x");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("make_worlds: --furnished seed 1x: not an integer in [0, 999999999]"), std::string::npos)
      << r.out;
  r = run(kMakeWorlds + " " + tmp.path + " --bogus");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("make_worlds: unknown option --bogus"), std::string::npos) << r.out;
  r = run(kMakeWorlds + " --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: make_worlds", 0), 0u) << r.out;
  r = run(kMakeWorlds + " " + tmp.path + "/no_dir --furnished 1");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/no_dir/furnished_1.stl: cannot write: the directory " + tmp.path +
                       "/no_dir does not exist"),
            std::string::npos)
      << r.out;
  r = run(kMakeWorlds + " " + tmp.path + " --furnished 1");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(exists(tmp.path + "/furnished_1.stl"));
}
