// coverage_oracle on bad arguments and bad input (issue #22 class 7: the one option parser, strict
// numbers, --help before anything else) and its --json output (valid JSON, no bare nan).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/stl_io.h"
#include "test_rooms.h"

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& cmd) { return scanstop::test_util::runCommand(cmd); }

/// A 3 x 3 m room, interior [0, 3]^2, its floor reaching 0.5 m beyond the walls, as an STL file.
std::string writeSmallRoom(const TempDir& tmp) {
  const std::string path = tmp.path + "/small_room.stl";
  scanstop::writeStlBinary(path, scanstop::test_util::squareRoom(3.0, 0.6));
  return path;
}

const std::string kOracle = COVERAGE_ORACLE_EXE;

}  // namespace

TEST(CoverageOracleCli, BadArgumentsAreNamedWithTheAllowedValues) {
  const std::string world = std::string(SCANSTOP_WORLDS_DIR) + "/room_10x8.stl";
  CliRun r = run(kOracle + " " + world + " --grid 0.5abc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("coverage_oracle: --grid 0.5abc: not a number in [0.05, 10]"), std::string::npos) << r.out;
  r = run(kOracle + " " + world + " --planes 37");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--planes 37: must be one of 50, 100, 200, 400"), std::string::npos) << r.out;
  r = run(kOracle + " " + world + " --start 1,nan,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--start 1,nan,0: value 2 ('nan')"), std::string::npos) << r.out;
  r = run(kOracle + " " + world + " --surface-cell 0.02 --surface-tolerance 0.03");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--surface-tolerance 0.03 is larger than the surface cell 0.02"), std::string::npos) << r.out;
  r = run(kOracle + " " + world + " --cell 0.12");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--cell 0.12 is not a whole multiple of --raster 0.05"), std::string::npos) << r.out;
  r = run(kOracle + " " + world + " --frobnicate");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("coverage_oracle: unknown option --frobnicate"), std::string::npos) << r.out;
  r = run(kOracle);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("WORLD.stl is required"), std::string::npos) << r.out;
  r = run(kOracle + " /nonexistent.stl --grid 0.5abc --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: coverage_oracle", 0), 0u) << r.out;
}

TEST(CoverageOracleCli, AMissingWorldAStartInAWallAndAnUnknownWorldAreNamed) {
  TempDir tmp("coverage_oracle_cli_test");
  const std::string room = writeSmallRoom(tmp);
  CliRun r = run(kOracle + " " + tmp.path + "/missing.stl");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/missing.stl: the world file does not exist"), std::string::npos) << r.out;
  r = run(kOracle + " " + room + " --start 3.0,1.5,0");  // the east wall
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("into an obstacle"), std::string::npos) << r.out;
  r = run(kOracle + " " + room + " --start 0.28,1.5,0");  // the simulator's 0.26 m disc fits, the 0.3 m one does not
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("the robot disc does not fit at the start"), std::string::npos) << r.out;
  r = run(kOracle + " " + room);  // no documented start pose for it
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("no documented start pose for world 'small_room'"), std::string::npos) << r.out;
}

TEST(CoverageOracleCli, JsonIsValidJsonAndTheTextNamesTheCounts) {
  TempDir tmp("coverage_oracle_cli_test");
  const std::string base = kOracle + " " + writeSmallRoom(tmp) + " --start 1.5,1.5,0 --grid 1 --planes 50 --quiet";
  CliRun r = run(base + " --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"floor\": {\"total\": "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"scans\": {\"90\": 1, \"95\": 1, \"99\": 1}"), std::string::npos) << r.out;
  r = run(base +
          " --json | python3 -c 'import json, sys; d = json.load(sys.stdin); print(\"parsed\", "
          "d[\"floor\"][\"scans\"][\"99\"])'");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("parsed 1"), std::string::npos) << r.out;
  r = run(base);
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("reachable floor: "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("floor     90 %: 1  95 %: 1  99 %: 1"), std::string::npos) << r.out;
}
