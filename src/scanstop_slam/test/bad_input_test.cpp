// Bad input to the SLAM core and to slam/register_scan's message checks: every case is refused with
// a message saying what was wrong, and a refused scan changes nothing (map, poses, map directory).
#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <stdlib.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_slam/icp_slam.h"
#include "scanstop_slam/request_check.h"

namespace scanstop {
namespace slam {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

/// A 6 x 5 m room with a box, seen from base_link at the origin.
PointCloud roomScan(int n = 20000) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    const float a = u(rng), b = u(rng);
    switch (i % 5) {
      case 0:
        c.points.emplace_back(-3.0f, 5 * a - 2.5f, 2.5f * b);
        break;
      case 1:
        c.points.emplace_back(6 * a - 3, 2.5f, 2.5f * b);
        break;
      case 2:
        c.points.emplace_back(6 * a - 3, -2.5f, 2.5f * b);
        break;
      case 3:
        c.points.emplace_back(1.0f + 0.5f * a, 0.5f, 0.8f * b);
        break;
      default:
        c.points.emplace_back(1.0f, 0.5f * a, 0.8f * b);
        break;
    }
  }
  c.setUnorganized();
  return c;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string tempDir() {
  char pattern[] = "/tmp/scanstop_slam_bad_input_XXXXXX";
  return mkdtemp(pattern);
}

// ---------------------------------------------------------------------------------------------
// Core: scanProblem, odomProblem, registerScan refusing without changing anything.

TEST(ScanProblem, AcceptsAScanWithNaNBeamsAndRefusesEmptyAllNaNInfAndFarPoints) {
  PointCloud scan = roomScan(100);
  scan.points[3] = Eigen::Vector3f(kNaN, kNaN, kNaN);  // a beam without a return is normal
  EXPECT_EQ(scanProblem(scan, 100.0), "");

  EXPECT_TRUE(contains(scanProblem(PointCloud(), 100.0), "no points"));

  PointCloud nan_only;
  nan_only.points.assign(10, Eigen::Vector3f(kNaN, kNaN, kNaN));
  nan_only.setUnorganized();
  EXPECT_TRUE(contains(scanProblem(nan_only, 100.0), "no finite point")) << scanProblem(nan_only, 100.0);

  PointCloud inf = roomScan(100);
  inf.points[42] = Eigen::Vector3f(1.0f, kInf, 0.0f);
  const std::string p = scanProblem(inf, 100.0);
  EXPECT_TRUE(contains(p, "point 42")) << p;
  EXPECT_TRUE(contains(p, "infinite")) << p;

  PointCloud far = roomScan(100);
  far.points[7] = Eigen::Vector3f(5000.0f, 0.0f, 0.0f);
  const std::string q = scanProblem(far, 100.0);
  EXPECT_TRUE(contains(q, "point 7")) << q;
  EXPECT_TRUE(contains(q, "max_point_distance")) << q;
  EXPECT_EQ(scanProblem(far, 6000.0), "");
}

TEST(SlamConfig, RefusesOutOfRangeRequestLimits) {
  SlamConfig c;
  c.max_odom_jump_m = -1.0;
  try {
    c.validate();
    FAIL() << "accepted max_odom_jump = -1";
  } catch (const ConfigError& e) {
    EXPECT_TRUE(contains(e.what(), "max_odom_jump")) << e.what();
    EXPECT_TRUE(contains(e.what(), "-1")) << e.what();
  }
  c = SlamConfig();
  c.max_point_distance_m = std::nan("");
  EXPECT_THROW(c.validate(), ConfigError);
}

/// Registers a first scan, then tries a bad one: refused with `expect` in the message, and the map,
/// the scan count, the last pose and the map directory are unchanged; a good scan then gets index 1.
void expectRefused(const PointCloud& bad, const Pose2D& odom, const std::string& expect,
                   const Eigen::Vector3d& origin = Eigen::Vector3d(0, 0, 0.45), double stamp = 10.0) {
  const std::string dir = tempDir();
  IcpSlam slam(SlamConfig(), dir + "/map");
  slam.registerScan(roomScan(), Pose2D(0, 0, 0), Eigen::Vector3d(0, 0, 0.45), 1.0);
  const size_t map_points = slam.map().size();
  const std::string poses = readFile(dir + "/map/poses.csv");
  try {
    slam.registerScan(bad, odom, origin, stamp);
    ADD_FAILURE() << "accepted a bad scan (" << expect << ")";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(contains(e.what(), expect)) << e.what();
  }
  EXPECT_EQ(slam.scanCount(), 1u);
  EXPECT_EQ(slam.map().size(), map_points);
  EXPECT_EQ(slam.lastOdomPose().x, 0.0);
  EXPECT_EQ(readFile(dir + "/map/poses.csv"), poses);
  std::ifstream second(dir + "/map/scans/scan_0001.pcd");
  EXPECT_FALSE(second.good()) << "a refused scan left a file";
  EXPECT_EQ(slam.registerScan(roomScan(), Pose2D(0.05, 0, 0), Eigen::Vector3d(0, 0, 0.45), 20.0).index, 1u);
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

TEST(IcpSlamBadInput, InfinitePointIsRefusedAndNothingChanges) {
  PointCloud bad = roomScan();
  bad.points[100] = Eigen::Vector3f(kInf, 0, 0);
  expectRefused(bad, Pose2D(0.1, 0, 0), "infinite");
}

TEST(IcpSlamBadInput, AllNaNScanIsRefusedAndNothingChanges) {
  PointCloud bad;
  bad.points.assign(500, Eigen::Vector3f(kNaN, kNaN, kNaN));
  bad.setUnorganized();
  expectRefused(bad, Pose2D(0.1, 0, 0), "no finite point");
}

TEST(IcpSlamBadInput, AbsurdPointIsRefusedAndNothingChanges) {
  PointCloud bad = roomScan();
  bad.points[5] = Eigen::Vector3f(0, 1e6f, 0);
  expectRefused(bad, Pose2D(0.1, 0, 0), "max_point_distance");
}

TEST(IcpSlamBadInput, HundredMetreOdometryJumpIsRefusedAndNothingChanges) {
  expectRefused(roomScan(), Pose2D(100.0, 0, 0), "max_odom_jump");
}

TEST(IcpSlamBadInput, NonFiniteOdometryOriginAndStampAreRefused) {
  expectRefused(roomScan(), Pose2D(std::nan(""), 0, 0), "not finite");
  expectRefused(roomScan(), Pose2D(0.1, 0, 0), "sensor origin", Eigen::Vector3d(0, std::nan(""), 0.45));
  expectRefused(roomScan(), Pose2D(0.1, 0, 0), "stamp", Eigen::Vector3d(0, 0, 0.45), std::nan(""));
}

TEST(IcpSlamBadInput, FirstScanIsCheckedToo) {
  IcpSlam slam{SlamConfig()};
  PointCloud bad = roomScan();
  bad.points[0] = Eigen::Vector3f(-kInf, 0, 0);
  EXPECT_THROW(slam.registerScan(bad, Pose2D()), std::invalid_argument);
  EXPECT_EQ(slam.scanCount(), 0u);
  EXPECT_EQ(slam.map().size(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Map directory: a corrupt or truncated scan file is skipped by name; the other scans load.

TEST(IcpSlamMapDirectory, CorruptAndTruncatedScanFilesAreSkippedByName) {
  const std::string dir = tempDir();
  {
    IcpSlam slam(SlamConfig(), dir + "/map");
    for (int i = 0; i < 4; ++i)
      slam.registerScan(roomScan(), Pose2D(0.02 * i, 0, 0), Eigen::Vector3d(0, 0, 0.45), i * 10.0);
  }
  size_t full = 0;
  {
    IcpSlam clean(SlamConfig(), dir + "/map");
    full = clean.map().size();
    EXPECT_TRUE(clean.skippedScans().empty());
  }
  // Scan 1: garbage; scan 2: truncated to half its size.
  writeFileAtomic(dir + "/map/scans/scan_0001.pcd", "this is not a point cloud\n");
  const std::string scan2 = readFile(dir + "/map/scans/scan_0002.pcd");
  writeFileAtomic(dir + "/map/scans/scan_0002.pcd", scan2.substr(0, scan2.size() / 2));
  IcpSlam slam(SlamConfig(), dir + "/map");
  ASSERT_EQ(slam.skippedScans().size(), 2u);
  EXPECT_EQ(slam.skippedScans()[0].file, dir + "/map/scans/scan_0001.pcd");
  EXPECT_FALSE(slam.skippedScans()[0].reason.empty());
  EXPECT_EQ(slam.skippedScans()[1].file, dir + "/map/scans/scan_0002.pcd");
  EXPECT_EQ(slam.scanCount(), 4u) << "indices and poses are kept";
  EXPECT_NEAR(slam.lastOdomPose().x, 0.06, 1e-12);
  EXPECT_GT(slam.map().size(), 0u);
  EXPECT_LE(slam.map().size(), full);
  // It goes on: the next scan gets index 4.
  EXPECT_EQ(slam.registerScan(roomScan(), Pose2D(0.08, 0, 0), Eigen::Vector3d(0, 0, 0.45), 50.0).index, 4u);
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

TEST(IcpSlamMapDirectory, WhenEveryScanFileIsCorruptTheNextScanStartsTheMapAtTheNextIndex) {
  const std::string dir = tempDir();
  {
    IcpSlam slam(SlamConfig(), dir + "/map");
    for (int i = 0; i < 3; ++i)
      slam.registerScan(roomScan(), Pose2D(0.02 * i, 0, 0), Eigen::Vector3d(0, 0, 0.45), i * 10.0);
  }
  for (int i = 0; i < 3; ++i) writeFileAtomic(dir + "/map/scans/scan_000" + std::to_string(i) + ".pcd", "garbage\n");
  IcpSlam slam(SlamConfig(), dir + "/map");
  EXPECT_EQ(slam.skippedScans().size(), 3u);
  EXPECT_EQ(slam.map().size(), 0u);
  const Registration r = slam.registerScan(roomScan(), Pose2D(0.05, 0, 0), Eigen::Vector3d(0, 0, 0.45), 40.0);
  EXPECT_EQ(r.index, 3u) << "no index of a listed scan is reused";
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.map_pose.x, 0.05, 1e-9);
  EXPECT_GT(slam.map().size(), 0u);
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

TEST(IcpSlamMapDirectory, CorruptPosesFileIsReportedByName) {
  const std::string dir = tempDir();
  {
    IcpSlam slam(SlamConfig(), dir + "/map");
    slam.registerScan(roomScan(), Pose2D(), Eigen::Vector3d(0, 0, 0.45), 1.0);
  }
  const std::string poses = readFile(dir + "/map/poses.csv");
  writeFileAtomic(dir + "/map/poses.csv", poses.substr(0, poses.size() - 9));  // truncated last line
  // scanstop_common's MapDirectory refuses the file naming it, or (newer) skips the line and reports it.
  try {
    IcpSlam slam(SlamConfig(), dir + "/map");
    ASSERT_FALSE(slam.skippedScans().empty()) << "a truncated poses.csv went unreported";
    EXPECT_EQ(slam.skippedScans()[0].file, dir + "/map/poses.csv");
  } catch (const IoError& e) {
    EXPECT_TRUE(contains(e.what(), dir + "/map/poses.csv")) << e.what();
  }
  EXPECT_EQ(std::system(("rm -rf '" + dir + "'").c_str()), 0);
}

// ---------------------------------------------------------------------------------------------
// Message checks of slam/register_scan (before conversion).

sensor_msgs::PointCloud2 goodMsg() { return ros_conv::toMsg(roomScan(100), "base_link", ros::Time(1.0)); }

sensor_msgs::PointField* field(sensor_msgs::PointCloud2& m, const std::string& name) {
  for (auto& f : m.fields)
    if (f.name == name) return &f;
  return nullptr;
}

TEST(CloudLayoutProblem, AcceptsTheTakeScanLayoutAndPlainXyz) {
  PointCloud organized;
  organized.points.assign(6, Eigen::Vector3f(1, 2, 0.5f));
  organized.ranges.assign(6, 2.3f);
  organized.width = 3;
  organized.height = 2;
  EXPECT_EQ(cloudLayoutProblem(ros_conv::toMsg(organized, "base_link", ros::Time(1.0)), 1000), "");
  EXPECT_EQ(cloudLayoutProblem(goodMsg(), 1000), "");
}

TEST(CloudLayoutProblem, EmptyCloud) {
  sensor_msgs::PointCloud2 m = goodMsg();
  m.width = 0;
  m.row_step = 0;
  m.data.clear();
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "empty"));
}

TEST(CloudLayoutProblem, TooManyPoints) { EXPECT_TRUE(contains(cloudLayoutProblem(goodMsg(), 50), "more than 50")); }

TEST(CloudLayoutProblem, MissingZField) {
  sensor_msgs::PointCloud2 m = goodMsg();
  field(m, "z")->name = "intensity";
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "no 'z' field")) << cloudLayoutProblem(m, 1000);
}

TEST(CloudLayoutProblem, DuplicateField) {
  sensor_msgs::PointCloud2 m = goodMsg();
  field(m, "y")->name = "x";
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "'x' twice")) << cloudLayoutProblem(m, 1000);
}

TEST(CloudLayoutProblem, NonFloat32Fields) {
  sensor_msgs::PointCloud2 m = goodMsg();
  field(m, "y")->datatype = sensor_msgs::PointField::UINT8;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "'y' has datatype 2")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  field(m, "x")->datatype = sensor_msgs::PointField::FLOAT64;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "expected float32")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  field(m, "x")->count = 3;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "count 3")) << cloudLayoutProblem(m, 1000);
}

TEST(CloudLayoutProblem, WrongPointStep) {
  sensor_msgs::PointCloud2 m = goodMsg();
  m.point_step = 8;  // z at offset 8 no longer fits
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "outside point_step")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  m.point_step = 0;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "point_step is 0"));
}

TEST(CloudLayoutProblem, OverlappingFields) {
  sensor_msgs::PointCloud2 m = goodMsg();
  field(m, "y")->offset = 2;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "overlap")) << cloudLayoutProblem(m, 1000);
}

TEST(CloudLayoutProblem, DataSizeNotMatchingTheLayout) {
  sensor_msgs::PointCloud2 m = goodMsg();
  m.data.resize(m.data.size() - 5);
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "needs")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  m.data.resize(m.data.size() + 12);
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "needs")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  m.row_step -= 1;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "row_step")) << cloudLayoutProblem(m, 1000);
  m = goodMsg();
  m.height = 2;  // claims twice the points its data holds
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "needs")) << cloudLayoutProblem(m, 1000);
}

TEST(CloudLayoutProblem, BigEndian) {
  sensor_msgs::PointCloud2 m = goodMsg();
  m.is_bigendian = true;
  EXPECT_TRUE(contains(cloudLayoutProblem(m, 1000), "big-endian"));
}

TEST(PoseProblem, NaNInfAndNonUnitQuaternions) {
  geometry_msgs::Pose p = ros_conv::toPoseMsg(Pose2D(1, 2, 0.3));
  EXPECT_EQ(poseProblem(p, "odom_pose"), "");
  geometry_msgs::Pose bad = p;
  bad.position.x = std::nan("");
  EXPECT_TRUE(contains(poseProblem(bad, "odom_pose"), "odom_pose.position")) << poseProblem(bad, "odom_pose");
  bad = p;
  bad.position.z = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(contains(poseProblem(bad, "odom_pose"), "not finite"));
  bad = p;
  bad.orientation.w = std::nan("");
  EXPECT_TRUE(contains(poseProblem(bad, "odom_pose"), "orientation")) << poseProblem(bad, "odom_pose");
  bad = p;
  bad.orientation.w *= 2.0;
  EXPECT_TRUE(contains(poseProblem(bad, "odom_pose"), "not a unit quaternion")) << poseProblem(bad, "odom_pose");
  bad.orientation = geometry_msgs::Quaternion();  // all zero
  EXPECT_TRUE(contains(poseProblem(bad, "odom_pose"), "norm 0")) << poseProblem(bad, "odom_pose");
}

TEST(FrameProblem, WrongFrameIds) {
  EXPECT_EQ(frameProblem("base_link", "base_link", "the cloud"), "");
  EXPECT_EQ(frameProblem("", "base_link", "the cloud"), "");
  EXPECT_TRUE(contains(frameProblem("map", "base_link", "the cloud"), "'map', expected 'base_link'"));
  EXPECT_FALSE(frameProblem("", "odom", "odom_pose", false).empty());
}

}  // namespace
}  // namespace slam
}  // namespace scanstop
