// Ground-truth floor coverage (evaluation, scanstop_eval): the true reachable floor of a world mesh,
// and how much of it an explorer floor map holds (mission_node's true coverage, floor_coverage).
// Moved from scanstop_explorer's door_test with the code (issue #21 point 6).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_eval/ground_truth.h"
#include "scanstop_explorer/floor_map.h"

using namespace scanstop::eval;
using scanstop::Pose2D;
using scanstop::explorer::ExplorerConfig;
using scanstop::explorer::GridGeometry;
using scanstop::explorer::kFloor;

namespace {
/// Adds an axis-aligned box [lo, hi] as 12 triangles.
void addBox(scanstop::TriangleMesh& m, const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  const int b = static_cast<int>(m.vertices.size());
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  for (const auto& t : f) m.faces.emplace_back(b + t[0], b + t[1], b + t[2]);
}

/// Room x, y in [0, 4], corridor y in [-2.1, -0.1] behind a 0.1 m wall with a 0.9 m door
/// x in [0.4, 1.3]; outer walls; a floor slab (below the obstacle layer: the floor the robot stands on).
scanstop::TriangleMesh roomAndCorridor() {
  scanstop::TriangleMesh world;
  addBox(world, {-0.5f, -2.6f, -0.1f}, {4.5f, 4.5f, 0.0f});
  addBox(world, {-0.1f, -2.2f, 0.0f}, {0.0f, 4.1f, 2.5f});   // west
  addBox(world, {4.0f, -2.2f, 0.0f}, {4.1f, 4.1f, 2.5f});    // east
  addBox(world, {-0.1f, 4.0f, 0.0f}, {4.1f, 4.1f, 2.5f});    // north
  addBox(world, {-0.1f, -2.2f, 0.0f}, {4.1f, -2.1f, 2.5f});  // corridor south
  addBox(world, {-0.1f, -0.1f, 0.0f}, {0.4f, 0.0f, 2.5f});   // room south, west of the door
  addBox(world, {1.3f, -0.1f, 0.0f}, {4.1f, 0.0f, 2.5f});    // room south, east of the door
  return world;
}

// Issue #22 class 3: one vertex far away ended floor_coverage in an OpenCV assertion (the world's grid
// size overflowed int). The size is checked in double first and capped, naming the extent.
TEST(GroundTruth, AWorldTooLargeForTheGridIsRefusedByExtent) {
  scanstop::TriangleMesh w;
  w.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1e30f, 0}};
  w.faces = {{0, 1, 2}, {3, 4, 5}};
  GridGeometry mg;
  mg.resolution = 0.05;
  mg.width = 10;
  mg.height = 10;
  const cv::Mat nothing = cv::Mat::zeros(mg.height, mg.width, CV_8U);
  for (const float far : {1e30f, 5e4f}) {
    w.vertices[5] = Eigen::Vector3f(0, far, 0);
    try {
      groundTruthCoverage(w, Pose2D(0.5, 0.2, 0), nothing, mg, Pose2D(), 0.1);
      ADD_FAILURE() << "a world reaching " << far << " m was rasterised";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the world's extent x [0, 1] y [0, "), std::string::npos) << what;
      EXPECT_NE(what.find("more than the limit of 2e+07 cells"), std::string::npos) << what;
    }
  }
}

}  // namespace

TEST(GroundTruthCoverage, TheRobotDiscStaysOnTheFloor) {
  // A 4 x 4 m room (0.1 m walls) with a 1 m opening in its east wall, on a floor slab that reaches
  // `band` beyond the walls (like the real house's floor rectangle). A 0.5 m band is too narrow for
  // the 0.6 m disc, so the reachable floor is the room; a 1.2 m band is a ring the robot can drive.
  const auto world = [](float band) {
    scanstop::TriangleMesh w;
    addBox(w, {-0.1f - band, -0.1f - band, -0.1f}, {4.1f + band, 4.1f + band, 0.0f});
    addBox(w, {-0.1f, -0.1f, 0.0f}, {0.0f, 4.1f, 2.5f});  // west
    addBox(w, {-0.1f, -0.1f, 0.0f}, {4.1f, 0.0f, 2.5f});  // south
    addBox(w, {-0.1f, 4.0f, 0.0f}, {4.1f, 4.1f, 2.5f});   // north
    addBox(w, {4.0f, -0.1f, 0.0f}, {4.1f, 1.5f, 2.5f});   // east, south of the opening
    addBox(w, {4.0f, 2.5f, 0.0f}, {4.1f, 4.1f, 2.5f});    // east, north of it
    return w;
  };
  const Pose2D start(2.0, 2.0, 0.0);
  GridGeometry mg;
  mg.resolution = 0.05;
  mg.origin_x = -4.0;
  mg.origin_y = -4.0;
  mg.width = 160;
  mg.height = 160;
  const cv::Mat nothing_seen = cv::Mat::zeros(mg.height, mg.width, CV_8U);
  const GroundTruthCoverage narrow = groundTruthCoverage(world(0.5f), start, nothing_seen, mg, start, 0.3);
  const GroundTruthCoverage wide = groundTruthCoverage(world(1.2f), start, nothing_seen, mg, start, 0.3);
  EXPECT_GT(narrow.reachable_m2, 15.0);  // the room (16 m2 less the corners a disc cannot sweep)
  // and what the disc sweeps standing in the opening (under 0.5 m2), not the 9.4 m2 band outside.
  EXPECT_LE(narrow.reachable_m2, 17.0);
  EXPECT_GT(wide.reachable_m2, 16.0 + 20.0);  // the ring: (4.2 + 2.4)^2 - 4.2^2 = 25.9 m2 less its corners
  // No reachable cell lies off the floor slab.
  for (int r = 0; r < wide.reachable.rows; ++r)
    for (int c = 0; c < wide.reachable.cols; ++c)
      if (wide.reachable.at<uint8_t>(r, c)) {
        const Eigen::Vector2d p = wide.geometry.center({c, r});
        ASSERT_TRUE(p.x() > -1.3 - 0.05 && p.x() < 5.3 + 0.05 && p.y() > -1.3 - 0.05 && p.y() < 5.3 + 0.05)
            << p.transpose();
      }
}

TEST(GroundTruthCoverage, ARoomSeenWithoutTheCorridorBehindItsDoorIsNotFullyCovered) {
  // World: roomAndCorridor().
  const scanstop::TriangleMesh world = roomAndCorridor();
  const Pose2D start(2.0, 2.0, 0.0);
  // Explorer maps in the map frame (= the start pose): the room seen, the corridor not / also.
  GridGeometry mg;
  mg.resolution = 0.05;
  mg.origin_x = -3.0;
  mg.origin_y = -5.0;
  mg.width = 140;
  mg.height = 140;
  cv::Mat room_only = cv::Mat::zeros(mg.height, mg.width, CV_8U), both;
  for (int r = 0; r < mg.height; ++r)
    for (int c = 0; c < mg.width; ++c) {
      const Eigen::Vector2d w = mg.center({c, r}) + Eigen::Vector2d(2.0, 2.0);
      if (w.x() > 0 && w.x() < 4 && w.y() > 0 && w.y() < 4) room_only.at<uint8_t>(r, c) = kFloor;
    }
  both = room_only.clone();
  for (int r = 0; r < mg.height; ++r)
    for (int c = 0; c < mg.width; ++c) {
      const Eigen::Vector2d w = mg.center({c, r}) + Eigen::Vector2d(2.0, 2.0);
      if (w.x() > 0 && w.x() < 4 && w.y() > -2.1 && w.y() < 0) both.at<uint8_t>(r, c) = kFloor;
    }
  const GroundTruthCoverage a = groundTruthCoverage(world, start, room_only, mg, start, 0.3);
  const GroundTruthCoverage b = groundTruthCoverage(world, start, both, mg, start, 0.3);
  // Reachable: the room (16 m2) and the corridor (8 m2) less what a 0.3 m disc cannot sweep.
  EXPECT_GT(a.reachable_m2, 20.0);
  EXPECT_LT(a.reachable_m2, 24.5);
  EXPECT_NEAR(a.reachable_m2, b.reachable_m2, 1e-9);
  EXPECT_LT(a.coverage, 0.75);  // the corridor is a third of the floor
  EXPECT_GT(a.coverage, 0.6);
  EXPECT_GT(b.coverage, 0.99);
  // With a 0.5 m radius the 0.9 m door is too narrow: the corridor is not reachable floor.
  const GroundTruthCoverage c = groundTruthCoverage(world, start, room_only, mg, start, 0.5);
  EXPECT_LT(c.reachable_m2, 16.0);
  EXPECT_GT(c.coverage, 0.99);
  // Bad input is named.
  EXPECT_THROW(groundTruthCoverage(scanstop::TriangleMesh(), start, room_only, mg, start, 0.3), std::invalid_argument);
  EXPECT_THROW(groundTruthCoverage(world, Pose2D(0.2, -0.05, 0), room_only, mg, start, 0.3), std::invalid_argument);
  EXPECT_THROW(groundTruthCoverage(world, start, cv::Mat::zeros(3, 3, CV_8U), mg, start, 0.3), std::invalid_argument);
  // A map directory without scans (mission_node and floor_coverage read maps through this).
  const scanstop::test_util::TempDir empty("ground_truth_test");
  EXPECT_THROW(groundTruthCoverageOfMap(world, start, scanstop::MapDirectory(empty.path), 0.3), std::invalid_argument);
}

TEST(GroundTruthCoverage, TheReachableFloorIsTheOneCoverageIsMeasuredOn) {
  // reachableFloor() (the coverage oracle's floor, scanstop_eval) is groundTruthCoverage()'s reachable mask;
  // the disc's centres lie inside it, at least the radius from every blocked cell.
  const scanstop::TriangleMesh world = roomAndCorridor();
  const Pose2D start(2.0, 2.0, 0.0);
  GridGeometry mg;
  mg.width = mg.height = 10;
  const GroundTruthCoverage c = groundTruthCoverage(world, start, cv::Mat::zeros(10, 10, CV_8U), mg, start, 0.3);
  const ReachableFloor f = reachableFloor(world, start, 0.3);
  EXPECT_EQ(cv::countNonZero(f.reachable != c.reachable), 0);
  EXPECT_NEAR(f.reachable_m2, c.reachable_m2, 1e-9);
  EXPECT_EQ(cv::countNonZero(f.centres & (f.reachable == 0)), 0);
  EXPECT_GT(cv::countNonZero(f.centres), 0);
  cv::Mat dist;
  cv::distanceTransform(1 - f.blocked, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  double min_dist = 0.0;
  cv::minMaxLoc(dist, &min_dist, nullptr, nullptr, nullptr, f.centres);
  EXPECT_GE(min_dist * f.geometry.resolution, 0.3 - 1e-6);
  // A start in the wall is named.
  try {
    reachableFloor(world, Pose2D(0.2, -0.05, 0), 0.3);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the start (0.2"), std::string::npos) << e.what();
  }
}

TEST(GroundTruthCoverage, OfAMapDirectoryUsesTheExplorerConfigurationGiven) {
  // roomAndCorridor(), one scan at the start that saw a few floor points 1.5 m
  // around it: the floor map, and so the true coverage, depends on the explorer's configuration
  // (here the known-free disc under the robot), which mission_node reads from the explorer's
  // parameters (config/explorer.yaml), not the defaults.
  const scanstop::TriangleMesh world = roomAndCorridor();
  const Pose2D start(2.0, 2.0, 0.0);
  const scanstop::test_util::TempDir tmp("ground_truth_cfg_test");
  const std::string dir_path = tmp.path;
  {
    scanstop::MapDirectory dir(dir_path);
    scanstop::PointCloud scan;
    for (int i = 0; i < 360; ++i)
      scan.points.emplace_back(1.5f * std::cos(i * 0.01745f), 1.5f * std::sin(i * 0.01745f), 0.0f);
    scanstop::MapScanInfo info;
    info.index = 0;
    info.sensor_origin = Eigen::Vector3d(0, 0, 0.45);
    dir.append(info, scan);
  }
  const scanstop::MapDirectory map(dir_path);
  ExplorerConfig small, large;
  large.known_free_radius_m = 1.4;
  const GroundTruthCoverage a = groundTruthCoverageOfMap(world, start, map, 0.3);
  const GroundTruthCoverage b = groundTruthCoverageOfMap(world, start, map, 0.3, 0.1, nullptr, small);
  const GroundTruthCoverage c = groundTruthCoverageOfMap(world, start, map, 0.3, 0.1, nullptr, large);
  EXPECT_EQ(a.scans, 1u);
  EXPECT_NEAR(a.observed_m2, b.observed_m2, 1e-9);  // default configuration = the defaults given
  // The 1.4 m disc instead of 0.8 m: about pi (1.4^2 - 0.8^2) = 4.1 m2 more floor seen.
  EXPECT_GT(c.observed_m2, a.observed_m2 + 3.0) << a.observed_m2 << " vs " << c.observed_m2;
  EXPECT_NEAR(a.reachable_m2, c.reachable_m2, 1e-9);
}
