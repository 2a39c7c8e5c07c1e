#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
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

TEST(MapDirectory, CorruptPosesFileIsReportedByNameAndLine) {
  TempDir tmp;
  PointCloud cloud;
  cloud.push_back({1, 0, 0});
  {
    MapDirectory map(tmp.file("m"));
    map.append(info(0, Pose2D()), cloud);
    map.append(info(1, Pose2D()), cloud);
  }
  const std::string poses = tmp.file("m/poses.csv");
  std::string text = readFile(poses);
  const size_t last = text.rfind('\n', text.size() - 2);
  std::ofstream(poses) << text.substr(0, last + 1) << "1,scans/scan_0001.pcd,40,abc\n";
  expectIoError([&] { MapDirectory m(tmp.file("m")); }, poses, "line 3: expected 17");
  std::ofstream(poses) << "garbage\n";
  expectIoError([&] { MapDirectory m(tmp.file("m")); }, poses, "line 1: not a scanstop poses header");
  std::ofstream(poses) << text.substr(0, text.find('\n') + 1)
                       << "0,../../etc/passwd,0,0,0,0,0,0,0,0,0,0,1,0,0,0,0\n";
  expectIoError([&] { MapDirectory m(tmp.file("m")); }, poses, "must be a relative path");
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

}  // namespace
}  // namespace scanstop
