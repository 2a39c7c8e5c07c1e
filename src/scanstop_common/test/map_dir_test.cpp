#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cmath>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/map_dir.h"
#include "test_util.h"

namespace scanstop {
namespace {

using test::expectIoError;
using test::TempDir;

MapScanInfo info(uint32_t index, const Pose2D& map_pose) {
  MapScanInfo s;
  s.index = index;
  s.stamp_s = 40.0 * index;
  s.map_pose = map_pose;
  s.odom_pose = Pose2D(map_pose.x + 0.1, map_pose.y, map_pose.yaw);
  s.sensor_origin = Eigen::Vector3d(0.0, 0.0, 0.5);
  s.converged = index != 1;
  s.iterations = 7 + index;
  s.correspondences = 1000 + index;
  s.rms_m = 0.01;
  s.overlap = 0.9;
  return s;
}

TEST(MapDirectory, AppendAndReopenKeepsEveryScan) {
  TempDir tmp;
  const std::string dir = tmp.file("map");
  PointCloud cloud;
  cloud.push_back({1, 0, 0});
  cloud.push_back({NAN, NAN, NAN});
  cloud.push_back({0, 2, 1});
  {
    MapDirectory map(dir);
    EXPECT_EQ(map.size(), 0u);
    map.append(info(0, Pose2D(0, 0, 0)), cloud);
    map.append(info(1, Pose2D(1.0, 2.0, M_PI / 2)), cloud);
  }
  MapDirectory map(dir);
  ASSERT_EQ(map.size(), 2u);
  EXPECT_EQ(map.scans()[1].file, "scans/scan_0001.pcd");
  EXPECT_FALSE(map.scans()[1].converged);
  EXPECT_EQ(map.scans()[1].iterations, 8u);
  EXPECT_DOUBLE_EQ(map.scans()[1].map_pose.yaw, M_PI / 2);
  EXPECT_DOUBLE_EQ(map.scans()[0].sensor_origin.z(), 0.5);
  const PointCloud base = map.loadScan(1);
  EXPECT_EQ(base.size(), 2u);  // the NaN point is not stored
  const PointCloud in_map = map.loadScanInMap(1);
  // (1, 0, 0) in a robot at (1, 2) facing +y is (1, 3, 0) in the map.
  EXPECT_TRUE(in_map.points[0].isApprox(Eigen::Vector3f(1, 3, 0), 1e-6f));
  EXPECT_THROW(map.append(info(5, Pose2D()), cloud), IoError);
}

TEST(MapDirectory, CreatesMissingParentDirectories) {
  TempDir tmp;
  const std::string dir = tmp.file("run/not/there/map");
  MapDirectory map(dir);
  PointCloud cloud;
  cloud.push_back({1, 0, 0});
  map.append(info(0, Pose2D()), cloud);
  EXPECT_EQ(MapDirectory(dir).size(), 1u);
  // A parent that is a file is reported by name.
  writeFileAtomic(tmp.file("file"), "x");
  expectIoError([&] { MapDirectory bad(tmp.file("file") + "/map"); }, tmp.file("file"), "directory");
}

TEST(MapDirectory, UpdateInfoRewritesPoses) {
  TempDir tmp;
  PointCloud cloud;
  cloud.push_back({1, 0, 0});
  MapDirectory map(tmp.file("m"));
  map.append(info(0, Pose2D()), cloud);
  MapScanInfo s = map.scans()[0];
  s.map_pose = Pose2D(0.5, 0.25, 0.1);
  map.updateInfo(s);
  EXPECT_DOUBLE_EQ(MapDirectory(tmp.file("m")).scans()[0].map_pose.x, 0.5);
}

TEST(MapDirectory, UpdatePosesRewritesPosesAndKeepsTheOldOnesInTheHistory) {
  TempDir tmp;
  PointCloud cloud;
  cloud.push_back({1, 0, 0});
  const std::string dir = tmp.file("m");
  {
    MapDirectory map(dir);
    for (uint32_t i = 0; i < 3; ++i) map.append(info(i, Pose2D(i, 0, 0.1 * i)), cloud);
    EXPECT_EQ(map.poseRevision(), 0u);
    // Scan 0's pose is given unchanged: it does not enter the history.
    EXPECT_EQ(map.updatePoses({{0, Pose2D(0, 0, 0)}, {1, Pose2D(1.5, 0.25, 0.2)}, {2, Pose2D(2.5, -0.5, 0.3)}}), 1u);
    EXPECT_EQ(map.updatePoses({{2, Pose2D(3.0, -1.0, 0.4)}}), 2u);
    EXPECT_EQ(map.updatePoses({{2, Pose2D(3.0, -1.0, 0.4)}}), 2u);  // nothing changed: no revision
    // Unknown scan or non-finite pose: refused, nothing changed.
    EXPECT_THROW(map.updatePoses({{1, Pose2D(9, 9, 0)}, {7, Pose2D()}}), IoError);
    EXPECT_THROW(map.updatePoses({{1, Pose2D(NAN, 0, 0)}}), IoError);
    EXPECT_DOUBLE_EQ(map.scans()[1].map_pose.x, 1.5);
    EXPECT_EQ(map.poseRevision(), 2u);
  }
  MapDirectory map(dir);
  ASSERT_EQ(map.size(), 3u);
  EXPECT_TRUE(map.problems().empty());
  EXPECT_EQ(map.poseRevision(), 2u);  // resumed from pose_history.csv
  EXPECT_DOUBLE_EQ(map.scans()[0].map_pose.x, 0.0);
  EXPECT_DOUBLE_EQ(map.scans()[1].map_pose.y, 0.25);
  EXPECT_DOUBLE_EQ(map.scans()[2].map_pose.x, 3.0);
  EXPECT_DOUBLE_EQ(map.scans()[2].map_pose.yaw, 0.4);
  EXPECT_DOUBLE_EQ(map.scans()[2].odom_pose.x, 2.1);  // the rest of the line stays
  EXPECT_EQ(map.scans()[2].iterations, 9u);
  EXPECT_EQ(readFile(map.poseHistoryPath()),
            "index,revision,map_x,map_y,map_yaw\n"
            "1,1,1,0,0.10000000000000001\n"
            "2,1,2,0,0.20000000000000001\n"
            "2,2,2.5,-0.5,0.29999999999999999\n");
  EXPECT_EQ(map.updatePoses({{0, Pose2D(0.125, 0, 0)}}), 3u);
}

/// A map of n scans (10 points each) in tmp/m; returns its directory.
std::string makeMap(const TempDir& tmp, uint32_t n) {
  PointCloud cloud;
  for (int i = 0; i < 100; ++i) cloud.push_back({0.01f * i, 1, 0});
  MapDirectory map(tmp.file("m"));
  for (uint32_t i = 0; i < n; ++i) map.append(info(i, Pose2D(i, 0, 0)), cloud);
  return tmp.file("m");
}

std::vector<uint32_t> indices(const MapDirectory& map) {
  std::vector<uint32_t> out;
  for (const auto& s : map.scans()) out.push_back(s.index);
  return out;
}

/// Expects exactly one problem, about `path`, containing `what`.
void expectOneProblem(const MapDirectory& map, const std::string& path, const std::string& what) {
  ASSERT_EQ(map.problems().size(), 1u);
  EXPECT_EQ(map.problems()[0].path, path) << map.problems()[0].message();
  EXPECT_NE(map.problems()[0].problem.find(what), std::string::npos) << map.problems()[0].message();
}

void replaceLine(const std::string& file, size_t line_no, const std::string& text) {
  std::istringstream in(readFile(file));
  std::string out, line;
  for (size_t n = 1; std::getline(in, line); ++n) out += (n == line_no ? text : line) + "\n";
  std::ofstream(file, std::ios::binary) << out;
}

/// Removes the map's journal: the map as written before the ledger existed (poses.csv alone), for the
/// tests of how poses.csv itself is read.
void dropJournal(const std::string& dir) { ASSERT_EQ(std::remove((dir + "/poses_journal.csv").c_str()), 0); }

TEST(MapDirectory, HealthyMapHasNoProblems) {
  TempDir tmp;
  const MapDirectory map(makeMap(tmp, 3));
  EXPECT_TRUE(map.problems().empty());
  EXPECT_EQ(map.nextIndex(), 3u);
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1, 2}));
}

TEST(MapDirectory, ScanCutInHalfIsReportedAndSkipped) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  const std::string scan = dir + "/scans/scan_0001.pcd";
  const std::string data = readFile(scan);
  std::ofstream(scan, std::ios::binary) << data.substr(0, data.size() / 2);
  PointCloud cloud;
  cloud.push_back({1, 1, 1});
  {
    MapDirectory map(dir);
    expectOneProblem(map, scan, "truncated PCD");
    EXPECT_NE(map.problems()[0].problem.find("scan 1 skipped"), std::string::npos);
    EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 2}));
    EXPECT_EQ(map.loadScan(1).size(), 100u);  // position 1 is scan 2
    EXPECT_EQ(map.nextIndex(), 3u);
    expectIoError([&] { map.append(info(2, Pose2D()), cloud); }, map.posesPath(), "the next index is 3");
    map.append(info(3, Pose2D()), cloud);
  }
  // The skipped scan's line stays in poses.csv (its pose is intact; the file may be restored).
  const MapDirectory again(dir);
  expectOneProblem(again, scan, "truncated PCD");
  EXPECT_EQ(indices(again), (std::vector<uint32_t>{0, 2, 3}));
  EXPECT_NE(readFile(again.posesPath()).find("\n1,scans/scan_0001.pcd,"), std::string::npos);
}

TEST(MapDirectory, ZeroByteScanIsReportedAndSkipped) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  std::ofstream(dir + "/scans/scan_0000.pcd", std::ios::trunc);
  const MapDirectory map(dir);
  expectOneProblem(map, dir + "/scans/scan_0000.pcd", "empty file; scan 0 skipped");
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{1}));
}

TEST(MapDirectory, MissingAndGarbageScansAreReportedAndSkipped) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  ASSERT_EQ(std::remove((dir + "/scans/scan_0000.pcd").c_str()), 0);
  std::ofstream(dir + "/scans/scan_0002.pcd", std::ios::binary) << "garbage\n";
  const MapDirectory map(dir);
  ASSERT_EQ(map.problems().size(), 2u);
  EXPECT_EQ(map.problems()[0].message(), dir + "/scans/scan_0000.pcd: no such file; scan 0 skipped");
  EXPECT_EQ(map.problems()[1].path, dir + "/scans/scan_0002.pcd");
  EXPECT_NE(map.problems()[1].problem.find("not a valid PCD file"), std::string::npos) << map.problems()[1].message();
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{1}));
}

TEST(MapDirectory, GarbageLineInPosesIsReportedSkippedAndRepaired) {
  TempDir tmp;
  // Without the journal (a map written before it); with it, see the ScanLedger tests.
  const std::string dir = makeMap(tmp, 3);
  dropJournal(dir);
  const std::string poses = dir + "/poses.csv";
  replaceLine(poses, 3, "1,scans/scan_0001.pcd,40,abc");
  PointCloud cloud;
  cloud.push_back({1, 1, 1});
  {
    MapDirectory map(dir);
    expectOneProblem(map, poses, "line 3: expected 17 comma-separated values, found 4; line skipped");
    EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 2}));
    EXPECT_EQ(map.nextIndex(), 3u);
    map.append(info(3, Pose2D()), cloud);  // rewrites poses.csv without the garbage line
  }
  EXPECT_EQ(readFile(poses).find("abc"), std::string::npos);
  const MapDirectory again(dir);
  // Scan 1's file is still there, now without a line: reported, not loaded.
  expectOneProblem(again, dir + "/scans/scan_0001.pcd", "not listed in poses.csv");
  EXPECT_EQ(indices(again), (std::vector<uint32_t>{0, 2, 3}));
}

TEST(MapDirectory, BadValuesInPosesAreReportedByLine) {
  TempDir tmp;
  // Without the journal (a map written before it); with it, see the ScanLedger tests.
  const std::string dir = makeMap(tmp, 5);
  dropJournal(dir);
  const std::string poses = dir + "/poses.csv";
  const std::string tail = ",0,0,0,0,0,0,0,0,0,1,0,0,0,0";
  replaceLine(poses, 2, "-1,scans/scan_0000.pcd,0" + tail);                        // negative index
  replaceLine(poses, 3, "1e300,scans/scan_0001.pcd,0" + tail);                     // huge index
  replaceLine(poses, 4, "2,../../etc/passwd,0" + tail);                            // outside the directory
  replaceLine(poses, 5, "3,scans/scan_0003.pcd,nan" + tail);                       // NaN stamp
  replaceLine(poses, 6, "1,scans/scan_0001.pcd,0,0,0,0,0,0,0,0,0,0,1,2.5,0,0,0");  // fractional count
  const MapDirectory map(dir);
  ASSERT_EQ(map.problems().size(), 5u + 2u);  // five lines, then the scan files no line names (2 and 4)
  const char* const expected[] = {
      "line 2: column 1 ('-1') is not an integer", "line 3: column 1 ('1e300') is not an integer",
      "line 4: scan file name '../../etc/passwd' must be a relative path",
      "line 5: column 3 ('nan') is not a finite number", "line 6: column 14 ('2.5') is not an integer"};
  for (size_t i = 0; i < 5; ++i) {
    EXPECT_EQ(map.problems()[i].path, poses);
    EXPECT_NE(map.problems()[i].problem.find(expected[i]), std::string::npos) << map.problems()[i].message();
  }
  EXPECT_TRUE(map.scans().empty());
  // Skipped lines whose first column is an index still count: lines 4, 5 and 6 name 2, 3 and 1.
  EXPECT_EQ(map.nextIndex(), 4u);
}

TEST(MapDirectory, DuplicateIndexKeepsTheFirstLine) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  const std::string poses = dir + "/poses.csv";
  std::ofstream(poses, std::ios::app) << "0,scans/scan_0001.pcd,0,9,9,0,0,0,0,0,0,0,1,0,0,0,0\n";
  const MapDirectory map(dir);
  expectOneProblem(map, poses, "line 4: scan index 0 already on line 2; line skipped");
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1}));
  EXPECT_DOUBLE_EQ(map.scans()[0].map_pose.x, 0.0);
}

// Found by map_dir_fuzzer: a line naming another index's file (1 -> scans/scan_0002.pcd, missing) made
// append(2) write that file, and the skipped scan 1 came back on reopening as a copy of scan 2.
TEST(MapDirectory, LineNamingAnotherScansFileIsNeverOverwritten) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  const std::string poses = dir + "/poses.csv";
  replaceLine(poses, 3, "1,scans/scan_0002.pcd,40,1,2,1.5,1.1,2,1.5,0,0,0.5,0,7,90,0.02,0.8");
  PointCloud cloud;
  cloud.push_back({1, 1, 1});
  {
    MapDirectory map(dir);
    ASSERT_EQ(map.problems().size(), 2u);
    EXPECT_EQ(map.problems()[0].message(), dir + "/scans/scan_0002.pcd: no such file; scan 1 skipped");
    EXPECT_NE(map.problems()[1].message().find("scan_0001.pcd: not listed in poses.csv"), std::string::npos);
    EXPECT_EQ(map.nextIndex(), 3u);  // 2 would write scans/scan_0002.pcd, which line 3 names
    map.append(info(3, Pose2D()), cloud);
  }

  const MapDirectory again(dir);
  EXPECT_EQ(indices(again), (std::vector<uint32_t>{0, 3}));
  // Two lines naming one file: the second is skipped.
  std::ofstream(poses, std::ios::app) << "7,scans/scan_0000.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  const MapDirectory third(dir);
  EXPECT_EQ(indices(third), (std::vector<uint32_t>{0, 3}));
  const std::string expected =
      poses + ": line 5: file scans/scan_0000.pcd already belongs to scan 0 (line 2); line skipped";
  EXPECT_TRUE(std::any_of(third.problems().begin(), third.problems().end(), [&](const MapProblem& p) {
    return p.message() == expected;
  })) << third.problems().front().message();
}

TEST(MapDirectory, AFileNameSpelledAnotherWayIsStillThatFile) {
  // Found by the map-directory fuzzer: a line naming "scans//scan_0001.pcd" was not recognised as
  // scans/scan_0001.pcd, so append() overwrote that scan's file and the reopened map lost a scan.
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  const std::string poses = dir + "/poses.csv";
  replaceLine(poses, 2, "0,./scans//scan_0001.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0");
  replaceLine(poses, 3, "1,scans/./scan_0000.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0");
  PointCloud cloud;
  cloud.push_back({7, 7, 7});
  {
    MapDirectory map(dir);
    EXPECT_TRUE(map.problems().empty()) << map.problems().front().message();
    ASSERT_EQ(map.size(), 2u);
    EXPECT_EQ(map.scans()[0].file, "scans/scan_0001.pcd");
    EXPECT_EQ(map.scans()[1].file, "scans/scan_0000.pcd");
    EXPECT_EQ(map.nextIndex(), 2u);  // scans/scan_0002.pcd is free; 0 and 1 are taken under other spellings
    map.append(info(2, Pose2D()), cloud);
  }
  const MapDirectory again(dir);
  EXPECT_EQ(indices(again), (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_NE(readFile(poses).find("0,scans/scan_0001.pcd,"), std::string::npos);  // rewritten in one spelling
  // Two spellings of one file on two lines: the second is skipped, as for one spelling.
  std::ofstream(poses, std::ios::app) << "7,scans//scan_0000.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  const MapDirectory third(dir);
  EXPECT_EQ(indices(third), (std::vector<uint32_t>{0, 1, 2}));
  // A name with nothing left after normalising is refused by line.
  std::ofstream(poses, std::ios::app) << "8,.//.,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  const MapDirectory fourth(dir);
  EXPECT_TRUE(std::any_of(fourth.problems().begin(), fourth.problems().end(), [](const MapProblem& p) {
    return p.problem.find("scan file name './/.' names no file") != std::string::npos;
  }));
}

TEST(MapDirectory, NextIndexAfterAppendSkipsANamedFile) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  // Scan 2's line names scans/scan_0004.pcd (missing): 3 is free, 4 is not.
  std::ofstream(dir + "/poses.csv", std::ios::app) << "2,scans/scan_0004.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  MapDirectory map(dir);
  EXPECT_EQ(map.nextIndex(), 3u);
  PointCloud cloud;
  cloud.push_back({1, 1, 1});
  map.append(info(3, Pose2D()), cloud);
  EXPECT_EQ(map.nextIndex(), 5u);
  EXPECT_EQ(MapDirectory(dir).nextIndex(), 5u);
}

TEST(MapDirectory, PosesCutMidLineKeepsTheCompleteLines) {
  TempDir tmp;
  // Without the journal (a map written before it); with it, see the ScanLedger tests.
  const std::string dir = makeMap(tmp, 3);
  dropJournal(dir);
  const std::string poses = dir + "/poses.csv";
  const std::string text = readFile(poses);
  std::ofstream(poses, std::ios::binary | std::ios::trunc) << text.substr(0, text.size() - 20);
  const MapDirectory map(dir);
  expectOneProblem(map, poses, "line 4: ");
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1}));
  EXPECT_EQ(map.nextIndex(), 3u);  // the cut line still names index 2
}

TEST(MapDirectory, EmptyOrHeaderlessPosesFile) {
  TempDir tmp;
  // Without the journal (a map written before it); with it, see the ScanLedger tests.
  const std::string dir = makeMap(tmp, 2);
  dropJournal(dir);
  const std::string poses = dir + "/poses.csv";
  const std::string text = readFile(poses);
  std::ofstream(poses, std::ios::trunc);
  {
    const MapDirectory map(dir);
    ASSERT_EQ(map.problems().size(), 3u);
    EXPECT_EQ(map.problems()[0].message(), poses + ": empty file (no header line); no scans loaded");
    EXPECT_EQ(map.problems()[1].path, dir + "/scans/scan_0000.pcd");
    EXPECT_NE(map.problems()[1].problem.find("not listed in poses.csv"), std::string::npos);
    EXPECT_EQ(map.size(), 0u);
    EXPECT_EQ(map.nextIndex(), 0u);
  }
  // Header lost, lines intact: the lines are read, the missing header reported.
  std::ofstream(poses, std::ios::trunc) << text.substr(text.find('\n') + 1);
  const MapDirectory map(dir);
  expectOneProblem(map, poses, "line 1: the header is missing; read as a scan line");
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1}));
  // A header that is garbage: skipped, the rest read.
  std::ofstream(poses, std::ios::trunc) << "garbage\n" << text.substr(text.find('\n') + 1);
  const MapDirectory map2(dir);
  expectOneProblem(map2, poses, "line 1: not the scanstop poses header; line skipped");
  EXPECT_EQ(map2.size(), 2u);
}

TEST(MapDirectory, InterruptedAppendLeavesAnOrphanThatTheNextScanReplaces) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 2);
  // The scan file of scan 2 was written, poses.csv not (the writer was killed in between).
  PointCloud cloud;
  cloud.push_back({5, 5, 5});
  writeCloud(dir + "/scans/scan_0002.pcd", cloud);
  MapDirectory map(dir);
  expectOneProblem(map, dir + "/scans/scan_0002.pcd", "not listed in poses.csv (an interrupted append?)");
  EXPECT_EQ(map.nextIndex(), 2u);
  cloud.points[0] = Eigen::Vector3f(6, 6, 6);
  map.append(info(2, Pose2D()), cloud);
  const MapDirectory again(dir);
  EXPECT_TRUE(again.problems().empty());
  EXPECT_EQ(again.loadScan(2).points.at(0), Eigen::Vector3f(6, 6, 6));
}

// The scan ledger (issue #22 class 8): poses.csv corrupted (a garbage line, the last line cut), then
// SLAM restarts and goes on: before the journal, scan 5's and scan 7's lines were lost for good (the
// mission counted 8 scans, the mesh used 6), and scan 7's file was even overwritten by the next scan.
TEST(ScanLedger, CorruptPosesPlusRestartKeepsEveryScanExactlyOnce) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 8);
  const std::string poses = dir + "/poses.csv";
  const std::vector<MapScanInfo> before = MapDirectory(dir).scans();
  ASSERT_EQ(before.size(), 8u);
  replaceLine(poses, 7, "5,scans/scan_0005.pcd,200,#garbage#");  // scan 5's line
  const std::string text = readFile(poses);
  std::ofstream(poses, std::ios::binary | std::ios::trunc) << text.substr(0, text.find("\n7,") + 2);  // "7," left
  PointCloud cloud;
  cloud.push_back({7, 7, 7});
  {
    MapDirectory restarted(dir);  // icp_slam_node restarted while the mission was paused
    EXPECT_EQ(indices(restarted), (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7}));
    EXPECT_EQ(restarted.restored(), (std::vector<uint32_t>{5, 7}));
    std::vector<std::string> messages;
    for (const MapProblem& p : restarted.problems()) messages.push_back(p.message());
    ASSERT_EQ(messages.size(), 4u) << messages.front();
    EXPECT_NE(
        messages[2].find(poses + ": scan 5 has no valid line in poses.csv; restored from poses_journal.csv line 7"),
        std::string::npos)
        << messages[2];
    EXPECT_NE(messages[3].find("scan 7 has no valid line in poses.csv; restored from poses_journal.csv line 9"),
              std::string::npos)
        << messages[3];
    EXPECT_EQ(restarted.nextIndex(), 8u);               // not 7: scan 7's file is never overwritten
    restarted.append(info(8, Pose2D(8, 0, 0)), cloud);  // the mission resumes: the next scan
  }
  const MapDirectory again(dir);
  EXPECT_TRUE(again.problems().empty()) << again.problems().front().message();
  ASSERT_EQ(indices(again), (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(again.scans()[i].file, before[i].file);
    EXPECT_EQ(again.scans()[i].map_pose.x, before[i].map_pose.x);
    EXPECT_EQ(again.scans()[i].stamp_s, before[i].stamp_s);
    EXPECT_EQ(again.loadScan(i).size(), 100u) << "scan " << i << " is the scan taken then";
  }
  EXPECT_EQ(again.loadScan(8).points.at(0), Eigen::Vector3f(7, 7, 7));
  // The count agrees with the scan files themselves: one file per scan, one scan per file.
  size_t files = 0;
  for (uint32_t i = 0; i < 12; ++i) {
    char name[64];
    std::snprintf(name, sizeof(name), "/scans/scan_%04u.pcd", i);
    struct stat st;
    if (::stat((dir + name).c_str(), &st) == 0) ++files;
  }
  EXPECT_EQ(files, again.size());
}

// The journal holds the latest pose of every scan: a relaxation's poses and an updateInfo come back.
TEST(ScanLedger, EmptiedPosesIsRestoredWithTheLatestPoses) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  {
    MapDirectory map(dir);
    ASSERT_EQ(map.updatePoses({{0, Pose2D(0.5, 0.25, 0.125)}, {2, Pose2D(2.5, 0, 0)}}), 1u);
    MapScanInfo again = map.scans()[1];
    again.map_pose = Pose2D(1.5, 0.5, 0.0);
    again.converged = true;
    map.updateInfo(again);
  }
  std::ofstream(dir + "/poses.csv", std::ios::trunc);
  const MapDirectory map(dir);
  ASSERT_EQ(indices(map), (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(map.scans()[0].map_pose.x, 0.5);
  EXPECT_EQ(map.scans()[0].map_pose.y, 0.25);
  EXPECT_EQ(map.scans()[1].map_pose.x, 1.5);
  EXPECT_TRUE(map.scans()[1].converged);
  EXPECT_EQ(map.scans()[2].map_pose.x, 2.5);
  EXPECT_EQ(map.nextIndex(), 3u);
  EXPECT_EQ(map.restored().size(), 3u);
}

// A map written before the journal: the first write seeds it with every line poses.csv holds.
TEST(ScanLedger, AMapWithoutAJournalGetsOneSeededWithEveryLine) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  dropJournal(dir);
  PointCloud cloud;
  cloud.push_back({1, 1, 1});
  MapDirectory(dir).append(info(3, Pose2D(3, 0, 0)), cloud);
  replaceLine(dir + "/poses.csv", 2, "garbage");  // scan 0's line
  const MapDirectory map(dir);
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(map.restored(), (std::vector<uint32_t>{0}));
}

// What the journal cannot vouch for is named, never silently used: a journal line naming another
// index's file, a line whose file poses.csv gives to another scan, a garbage journal line. A journal
// cut mid-line (a crash while appending) gets the next line on a line of its own.
TEST(ScanLedger, JournalLinesThatCannotBeTrustedAreNamedAndNotRestored) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  const std::string poses = dir + "/poses.csv";
  const std::string journal = dir + "/poses_journal.csv";
  {
    std::ofstream(journal, std::ios::app) << "1,scans/scan_0001.pcd,40,cut mid-li";  // no newline
    PointCloud cloud;
    cloud.push_back({1, 1, 1});
    MapDirectory(dir).append(info(3, Pose2D(3, 0, 0)), cloud);
  }
  std::ofstream(journal, std::ios::app) << "4,scans/scan_0002.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  replaceLine(poses, 3, "1,scans/scan_0003.pcd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0");  // scan 1's line names scan 3's file
  replaceLine(poses, 5, "garbage");                                              // scan 3's line
  const MapDirectory map(dir);
  std::string all;
  for (const MapProblem& p : map.problems()) all += p.message() + "\n";
  EXPECT_NE(all.find(journal + ": line 5: expected 17 comma-separated values, found 4; line ignored"),
            std::string::npos)
      << all;
  EXPECT_NE(
      all.find(journal + ": line 7: scan 4 has no valid line in poses.csv; the journal line names scans/scan_0002.pcd, "
                         "not scans/scan_0004.pcd; not restored"),
      std::string::npos)
      << all;
  EXPECT_NE(all.find("scan 3 has no valid line in poses.csv; its file scans/scan_0003.pcd belongs to scan 1 in "
                     "poses.csv; not restored"),
            std::string::npos)
      << all;
  EXPECT_TRUE(map.restored().empty());
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1, 2}));
}

TEST(MapDirectory, PosesPathThatIsNotAFileIsAnError) {
  TempDir tmp;
  ASSERT_EQ(::mkdir(tmp.file("m").c_str(), 0755), 0);
  ASSERT_EQ(::mkdir(tmp.file("m/poses.csv").c_str(), 0755), 0);
  expectIoError([&] { MapDirectory m(tmp.file("m")); }, tmp.file("m/poses.csv"), "not a regular file");
}

TEST(MapDirectory, TruncatedScanFileIsReportedByName) {
  TempDir tmp;
  PointCloud cloud;
  for (int i = 0; i < 100; ++i) cloud.push_back({0.1f * i, 0, 0});
  MapDirectory map(tmp.file("m"));
  map.append(info(0, Pose2D()), cloud);
  const std::string scan = tmp.file("m/scans/scan_0000.pcd");
  const std::string data = readFile(scan);
  std::ofstream(scan, std::ios::binary) << data.substr(0, data.size() / 2);
  try {
    map.loadScan(0);
    ADD_FAILURE() << "a truncated scan must not load";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(scan), std::string::npos) << e.what();
  }
}

// Issue #22 class 3: a pose 100 km away grew plan_step to 6 GB. Poses are bounds-checked when read
// (the line is refused, by number) and when appended.
TEST(MapDirectory, PosesBeyondTenKilometresAreRefusedByLine) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  std::string text = readFile(dir + "/poses.csv");
  const size_t at = text.find("\n2,scans/scan_0002.pcd,80,2,");
  ASSERT_NE(at, std::string::npos) << text;
  text.replace(at, std::string("\n2,scans/scan_0002.pcd,80,2,").size(), "\n2,scans/scan_0002.pcd,80,100000,");
  writeFileAtomic(dir + "/poses.csv", text);
  dropJournal(dir);  // poses.csv alone (the journal would restore the line)
  MapDirectory map(dir);
  expectOneProblem(map, dir + "/poses.csv", "line 4: map pose (columns 4-6) (x=100000 m");
  EXPECT_NE(map.problems()[0].problem.find("is beyond the 10000 m pose limit"), std::string::npos)
      << map.problems()[0].message();
  EXPECT_EQ(indices(map), (std::vector<uint32_t>{0, 1}));
  PointCloud cloud;
  cloud.push_back({1, 1, 0});
  expectIoError([&] { map.append(info(3, Pose2D(0, -20000, 0)), cloud); }, map.posesPath(),
                "cannot append scan 3: map pose (x=0 m, y=-20000 m, yaw=0 rad) is beyond the 10000 m pose limit");
  EXPECT_EQ(std::ifstream(dir + "/scans/scan_0003.pcd").good(), false) << "nothing written";
}

std::vector<std::string> warningsOf(const std::string& dir, bool skip_bad, size_t* scans = nullptr) {
  std::vector<std::string> warnings;
  const MapDirectory map = openMapForTool(dir, skip_bad, [&](const std::string& w) { warnings.push_back(w); });
  if (scans) *scans = map.size();
  return warnings;
}

// Issue #22 class 2: plan_step and icp_replay went on without a missing scan and exited 0.
TEST(OpenMapForTool, AMissingScanFileIsAnErrorNamingItUnlessSkipBad) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  ASSERT_EQ(std::remove((dir + "/scans/scan_0001.pcd").c_str()), 0);
  try {
    openMapForTool(dir, false, nullptr);
    ADD_FAILURE() << "a map with a missing scan file was loaded";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              dir + "/scans/scan_0001.pcd: no such file (1 problem in the map; --skip-bad loads the rest)");
  }
  size_t scans = 0;
  const std::vector<std::string> warnings = warningsOf(dir, true, &scans);
  EXPECT_EQ(scans, 2u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], "skipped: " + dir + "/scans/scan_0001.pcd: no such file; scan 1 skipped");
  TempDir healthy;
  EXPECT_TRUE(warningsOf(makeMap(healthy, 2), false).empty()) << "a healthy map loads without a word";
}

TEST(OpenMapForTool, ANaNPoseIsAnErrorNamingTheLine) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  std::string text = readFile(dir + "/poses.csv");
  const size_t at = text.find("\n1,scans/scan_0001.pcd,40,1,");
  ASSERT_NE(at, std::string::npos) << text;
  text.replace(at, std::string("\n1,scans/scan_0001.pcd,40,1,").size(), "\n1,scans/scan_0001.pcd,40,nan,");
  writeFileAtomic(dir + "/poses.csv", text);
  dropJournal(dir);  // poses.csv alone (the journal would restore the line)
  expectIoError([&] { openMapForTool(dir, false, nullptr); },
                dir + "/poses.csv: line 3: column 4 ('nan') is not a finite number", "--skip-bad loads the rest");
  size_t scans = 0;
  const std::vector<std::string> warnings = warningsOf(dir, true, &scans);
  EXPECT_EQ(scans, 2u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("line 3: column 4 ('nan') is not a finite number; line skipped"), std::string::npos);
}

// Issue #22 class 8 seen from a tool: poses.csv lost its last line (cut mid-line), the scan ledger has
// it. A read-only tool names the line and says the ledger holds it; --skip-bad loads every scan (the
// restored one too) and says what was repaired.
TEST(OpenMapForTool, ALineTheJournalRestoresIsNamedAndLoadedWithSkipBad) {
  TempDir tmp;
  const std::string dir = makeMap(tmp, 3);
  const std::string text = readFile(dir + "/poses.csv");
  writeFileAtomic(dir + "/poses.csv", text.substr(0, text.find("\n2,") + 8));  // "2,scans/" left
  expectIoError([&] { openMapForTool(dir, false, nullptr); }, dir + "/poses.csv: line 4: expected 17",
                "--skip-bad loads the rest, with the lines poses_journal.csv restores");
  std::vector<std::string> warnings;
  const MapDirectory map = openMapForTool(dir, true, [&](const std::string& w) { warnings.push_back(w); });
  EXPECT_EQ(map.size(), 3u);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("repaired: " + dir + "/poses.csv: line 4: ", 0), 0u) << warnings[0];
  EXPECT_NE(warnings[1].find("scan 2 has no valid line in poses.csv; restored from poses_journal.csv"),
            std::string::npos)
      << warnings[1];
  // Without the ledger the line is skipped, not repaired (and scan 2's file is one no line names).
  dropJournal(dir);
  warnings.clear();
  EXPECT_EQ(openMapForTool(dir, true, [&](const std::string& w) { warnings.push_back(w); }).size(), 2u);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("skipped: " + dir + "/poses.csv: line 4: ", 0), 0u) << warnings[0];
  EXPECT_EQ(warnings[1],
            "skipped: " + dir + "/scans/scan_0002.pcd: not listed in poses.csv (an interrupted append?); not loaded");
}

TEST(OpenMapForTool, CreatesNothingAndNamesAMissingOrForeignDirectory) {
  TempDir tmp;
  // `icp_replay --help` created --help/scans before: a tool never creates the map it reads.
  expectIoError([&] { openMapForTool(tmp.file("--help"), false, nullptr); }, tmp.file("--help"),
                "no such map directory");
  struct stat st;
  EXPECT_NE(::stat(tmp.file("--help").c_str(), &st), 0);
  ASSERT_EQ(::mkdir(tmp.file("plain").c_str(), 0755), 0);
  expectIoError([&] { openMapForTool(tmp.file("plain"), false, nullptr); }, tmp.file("plain/poses.csv"),
                "does not exist: not a map directory");
  EXPECT_NE(::stat(tmp.file("plain/scans").c_str(), &st), 0);
  tmp.write("file.txt", "x");
  expectIoError([&] { openMapForTool(tmp.file("file.txt"), false, nullptr); }, tmp.file("file.txt"), "not a directory");
}

}  // namespace
}  // namespace scanstop
