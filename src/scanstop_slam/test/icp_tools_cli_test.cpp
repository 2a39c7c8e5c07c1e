// The icp_register, icp_replay and relax_bench command-line tools on bad input (issue #22): strict options and
// --help (class 7), strict map loading with --skip-bad (class 2), messages naming the file (class 6).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"

using namespace scanstop;

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& cmd) { return scanstop::test_util::runCommand(cmd); }

bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// The walls, floor and ceiling of a 4 x 3 x 2 m room around the origin, 10 cm apart.
PointCloud room() {
  PointCloud c;
  for (double a = -2.0; a <= 2.0; a += 0.1)
    for (double b = -1.5; b <= 1.5; b += 0.1) {
      c.push_back({static_cast<float>(a), static_cast<float>(b), 0.0f});
      c.push_back({static_cast<float>(a), static_cast<float>(b), 2.0f});
    }
  for (double a = -2.0; a <= 2.0; a += 0.1)
    for (double z = 0.1; z < 2.0; z += 0.1) {
      c.push_back({static_cast<float>(a), -1.5f, static_cast<float>(z)});
      c.push_back({static_cast<float>(a), 1.5f, static_cast<float>(z)});
    }
  for (double b = -1.5; b <= 1.5; b += 0.1)
    for (double z = 0.1; z < 2.0; z += 0.1) {
      c.push_back({-2.0f, static_cast<float>(b), static_cast<float>(z)});
      c.push_back({2.0f, static_cast<float>(b), static_cast<float>(z)});
    }
  return c;
}

std::string makeMap(const std::string& dir, size_t scans) {
  MapDirectory map(dir);
  for (size_t i = 0; i < scans; ++i) {
    MapScanInfo info;
    info.index = static_cast<uint32_t>(i);
    info.stamp_s = 10.0 * i;
    info.map_pose = info.odom_pose = Pose2D(0.05 * i, 0.0, 0.0);
    map.append(info, room());
  }
  return dir;
}

/// A mission_state.yaml whose scans 0 .. scans-1 all truly stand at the origin.
void writeTruthAtOrigin(const std::string& path, size_t scans) {
  std::string truth = "scans:\n";
  for (size_t i = 0; i < scans; ++i) truth += "  - index: " + std::to_string(i) + "\n    true_pose: [0, 0, 0]\n";
  writeFileAtomic(path, truth);
}

const std::string kRegister = ICP_REGISTER_EXE;
const std::string kReplay = ICP_REPLAY_EXE;
const std::string kRelaxBench = RELAX_BENCH_EXE;

}  // namespace

// Class 7: "--max-iterations 99999999999" answered "stoi"; "--c-max 0.1abc" and "--voxel -1" ran
// silently; "--init nan,..." was accepted and --json then printed bare nan (invalid JSON).
TEST(IcpRegisterCli, NumbersAreStrictAndJsonStaysJson) {
  TempDir tmp("icp_tools_cli_test");
  writeCloud(tmp.file("room.pcd"), room());
  const std::string base = kRegister + " " + tmp.file("room.pcd") + " " + tmp.file("room.pcd");
  CliRun r = run(base + " --max-iterations 99999999999");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("icp_register: --max-iterations 99999999999: not an integer in [1, 10000]"), std::string::npos)
      << r.out;
  r = run(base + " --c-max 0.1abc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--c-max 0.1abc: not a number in [0.001, 5]"), std::string::npos) << r.out;
  r = run(base + " --voxel -1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--voxel -1: not a number in [0, 10]"), std::string::npos) << r.out;
  r = run(base + " --init nan,0,0,0 --json");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--init nan,0,0,0: value 1 ('nan') is not a number"), std::string::npos) << r.out;
  r = run(base + " --frobnicate");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("icp_register: unknown option --frobnicate"), std::string::npos) << r.out;
  r = run(kRegister + " --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: icp_register", 0), 0u) << r.out;
  r = run(base + " --init 0.05,0,0,1 --json");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;
  for (const char* bare : {": inf", "-inf", "[inf", " inf,", " inf]", " inf}"})
    EXPECT_EQ(r.out.find(bare), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"converged\": true"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"failure\": \"\""), std::string::npos) << r.out;
}

// Class 6: a directory given as an input file said "empty file"; a missing path without an extension
// "unknown point-cloud format '.'".
TEST(IcpRegisterCli, InputsAreNamedWithWhatIsWrong) {
  TempDir tmp("icp_tools_cli_test");
  writeCloud(tmp.file("room.pcd"), room());
  ASSERT_EQ(::mkdir(tmp.file("dir.pcd").c_str(), 0755), 0);
  CliRun r = run(kRegister + " " + tmp.file("dir.pcd") + " " + tmp.file("room.pcd"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.file("dir.pcd") + ": is a directory, not a file"), std::string::npos) << r.out;
  r = run(kRegister + " " + tmp.file("room.pcd") + " " + tmp.file("nothing"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.file("nothing") + ": no such file"), std::string::npos) << r.out;
}

// Class 7: `icp_replay --help` created a folder named --help/scans; a missing map directory was created.
TEST(IcpReplayCli, HelpAndAMissingMapCreateNothing) {
  TempDir tmp("icp_tools_cli_test");
  CliRun r = run("cd " + tmp.path + " && " + kReplay + " --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: icp_replay", 0), 0u) << r.out;
  EXPECT_FALSE(exists(tmp.file("--help")));
  r = run(kReplay + " " + tmp.file("no_map") + " --quiet");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.file("no_map") + ": no such map directory"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(tmp.file("no_map")));
  r = run(kReplay + " " + tmp.file("no_map") + " --max-iterations 99999999999");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--max-iterations 99999999999: not an integer in [1, 10000]"), std::string::npos) << r.out;
  r = run(kReplay + " " + tmp.file("no_map") + " --relax-loss fancy");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--relax-loss fancy: must be one of cauchy, huber, none"), std::string::npos) << r.out;
  EXPECT_FALSE(exists(tmp.file("no_map")));
}

// Class 2: icp_replay on a map with a missing scan file went on with the rest and exited 0.
TEST(IcpReplayCli, AMissingScanFileIsRefusedByNameUnlessSkipBad) {
  TempDir tmp("icp_tools_cli_test");
  const std::string map = makeMap(tmp.file("map"), 3);
  ASSERT_EQ(std::remove((map + "/scans/scan_0001.pcd").c_str()), 0);
  CliRun r = run(kReplay + " " + map + " --quiet");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("icp_replay: " + map +
                       "/scans/scan_0001.pcd: no such file (1 problem in the map; --skip-bad loads the rest)"),
            std::string::npos)
      << r.out;
  r = run(kReplay + " " + map + " --quiet --skip-bad");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("icp_replay: warning: skipped: " + map + "/scans/scan_0001.pcd: no such file; scan 1 skipped"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("2 scans,"), std::string::npos) << r.out;
}

// Class 6: a garbage ground-truth file gave a yaml-cpp line and column without the file name.
TEST(IcpReplayCli, ABadTruthFileIsNamed) {
  TempDir tmp("icp_tools_cli_test");
  const std::string map = makeMap(tmp.file("map"), 1);
  writeFileAtomic(tmp.file("garbage.yaml"), "scans: [ {index: 0, true_pose: [1, 2\n");
  CliRun r = run(kReplay + " " + map + " --quiet --truth " + tmp.file("garbage.yaml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("icp_replay: " + tmp.file("garbage.yaml") + ": not valid YAML: yaml-cpp: error at line"),
            std::string::npos)
      << r.out;
  writeFileAtomic(tmp.file("huge.yaml"), "scans:\n  - index: 4000000000\n    true_pose: [0, 0, 0]\n");
  r = run(kReplay + " " + map + " --quiet --truth " + tmp.file("huge.yaml"));  // resized a vector to 4e9 before
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.file("huge.yaml") + ": scans[0]: index 4000000000 is not an integer from 0 to 9999999"),
            std::string::npos)
      << r.out;
  writeFileAtomic(tmp.file("nan.yaml"), "scans:\n  - index: 0\n    true_pose: [.nan, 0, 0]\n");
  r = run(kReplay + " " + map + " --quiet --truth " + tmp.file("nan.yaml"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.file("nan.yaml") + ": scans[0] (scan 0): true_pose"), std::string::npos) << r.out;
  r = run(kReplay + " " + map + " --quiet --truth " + tmp.path);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + ": is a directory, not a file"), std::string::npos) << r.out;
  writeFileAtomic(tmp.file("truth.yaml"), "scans:\n  - index: 0\n    true_pose: [0, 0, 0]\n");
  r = run(kReplay + " " + map + " --quiet --truth " + tmp.file("truth.yaml"));
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("error, odometry"), std::string::npos) << r.out;
}

// --isolated: each scan alone from the true pose before plus the odometry leg; --from N registers only
// scans N on. The scans all see the same room from the same place (true poses 0), odometry says
// 5 cm per scan: every registration comes back to the truth from a guess 5 cm off.
TEST(IcpReplayCli, IsolatedRegistersEachScanAloneAndFromSkipsTheEarlierOnes) {
  TempDir tmp("icp_tools_cli_test");
  const std::string map = makeMap(tmp.file("map"), 4);
  writeTruthAtOrigin(tmp.file("truth.yaml"), 4);
  CliRun r = run(kReplay + " " + map + " --isolated odometry");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.out.find("--isolated needs --truth"), std::string::npos) << r.out;
  r = run(kReplay + " " + map + " --truth " + tmp.file("truth.yaml") + " --isolated odometry");
  ASSERT_EQ(r.status, 0) << r.out;
  for (const char* line : {"scan   1: ok", "scan   2: ok", "scan   3: ok", "guess off   5.0 cm",
                           "isolated registrations from the odometry leg over 3 scans"})
    EXPECT_NE(r.out.find(line), std::string::npos) << line << "\n" << r.out;
  const size_t max_at = r.out.find("max ", r.out.find("isolated registrations"));
  ASSERT_NE(max_at, std::string::npos) << r.out;
  EXPECT_LT(std::stod(r.out.substr(max_at + 4)), 1.0) << r.out;  // cm: back at the truth
  r = run(kReplay + " " + map + " --truth " + tmp.file("truth.yaml") + " --isolated truth --from 3");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("scan   1:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("scan   3: ok"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("isolated registrations from the true pose over 1 scans"), std::string::npos) << r.out;
  r = run(kReplay + " " + map + " --truth " + tmp.file("truth.yaml") + " --from 3");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("--from needs --isolated"), std::string::npos) << r.out;
}

// Issue #17 point 4: relax_bench solves the relaxation's graph with ours and with PCL's LUM from the
// same start poses. The stored poses claim 5 cm per scan; every scan is really at the origin, and
// every edge (a pairwise registration of the same room) says so: both solvers bring the start
// poses' 9.4 cm RMS / 15 cm max back to the truth.
TEST(RelaxBenchCli, BothSolversCorrectTheStoredPosesOnTheSameGraph) {
  TempDir tmp("icp_tools_cli_test");
  const std::string map = makeMap(tmp.file("map"), 4);
  writeTruthAtOrigin(tmp.file("truth.yaml"), 4);
  CliRun r = run(kRelaxBench + " " + map);
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("--truth mission_state.yaml is required"), std::string::npos) << r.out;
  r = run(kRelaxBench + " " + map + " --truth " + tmp.file("truth.yaml") + " --lum-rounds 0");
  EXPECT_EQ(r.status, 2) << r.out;
  r = run(kRelaxBench + " " + map + " --truth " + tmp.file("missing.yaml"));
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("missing.yaml"), std::string::npos) << r.out;
  r = run(kRelaxBench + " " + map + " --truth " + tmp.file("truth.yaml"));
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("4 scans, 3 edges"), std::string::npos) << r.out;
  const auto rmsOf = [&](const std::string& row) {
    const size_t at = r.out.find(row);
    if (at == std::string::npos) return -1.0;
    const size_t v = r.out.find("ATE RMS", at);
    return v == std::string::npos ? -1.0 : std::stod(r.out.substr(v + 7));
  };
  EXPECT_NEAR(rmsOf("start poses"), 9.35, 0.01) << r.out;
  const double ours = rmsOf("ours (PoseGraph"), lum = rmsOf("PCL LUM (6 dof");
  EXPECT_GE(ours, 0.0) << r.out;
  EXPECT_LT(ours, 0.5) << r.out;  // cm
  EXPECT_GE(lum, 0.0) << r.out;
  EXPECT_LT(lum, 0.5) << r.out;
  // The edges against the true poses (all 3 are chain edges here, each right to under a millimetre),
  // and the graph solved from the truth stays there.
  const size_t chain = r.out.find("edges at the true poses, chain    3: position RMS");
  ASSERT_NE(chain, std::string::npos) << r.out;
  EXPECT_LT(std::stod(r.out.substr(chain + 49)), 0.1) << r.out;  // cm
  EXPECT_NE(r.out.find("edges at the true poses, loop     0"), std::string::npos) << r.out;
  const double from_truth = rmsOf("ours from the true poses");
  EXPECT_GE(from_truth, 0.0) << r.out;
  EXPECT_LT(from_truth, 0.1) << r.out;
}
