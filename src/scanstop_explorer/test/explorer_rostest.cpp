// Wiring test of explorer_node: publishes synthetic registered scans of a two-room world (as
// icp_slam_node would), calls explorer/plan_next and checks the plan against the true world.
#include <gtest/gtest.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <scanstop_msgs/PlanNext.h>
#include <scanstop_msgs/RegisteredScan.h>
#include <visualization_msgs/Marker.h>

#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "scanstop_common/error.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_explorer/distance_transform.h"
#include "scanstop_explorer/explorer_ros.h"
#include "scenes.h"

using namespace scanstop;
using namespace scanstop::explorer;

namespace {
constexpr double kRange = 3.0;

scanstop_msgs::RegisteredScan scanMsg(const test::Scene& world, uint32_t index, const Pose2D& pose) {
  scanstop_msgs::RegisteredScan msg;
  msg.header.frame_id = "map";
  msg.header.stamp = ros::Time::now();
  msg.scan_index = index;
  msg.pose = ros_conv::toPoseStamped(pose, "map", msg.header.stamp);
  msg.sensor_origin.x = pose.x;
  msg.sensor_origin.y = pose.y;
  msg.sensor_origin.z = 0.4;
  PointCloud cloud;
  for (const auto& p : test::simulateScan(world, {pose.x, pose.y}, kRange)) cloud.push_back(p);
  msg.cloud = ros_conv::toMsg(cloud, "map", msg.header.stamp);
  msg.registration_ok = true;
  return msg;
}

/// Minimum clearance [m] along the path in the true world (distance of sample points to non-free cells).
double clearance(const test::Scene& world, const std::vector<Eigen::Vector2d>& path) {
  const cv::Mat d = distanceTransform(world.free);
  double worst = 1e9;
  for (size_t i = 1; i < path.size(); ++i)
    for (int k = 0; k <= 100; ++k) {
      const Eigen::Vector2d p = path[i - 1] + (path[i] - path[i - 1]) * (k / 100.0);
      const cv::Point c = world.geometry.cellOf(p.x(), p.y());
      if (!world.geometry.contains(c)) return 0.0;
      worst = std::min(worst, d.at<float>(c) * world.geometry.resolution);
    }
  return worst;
}

std::vector<Eigen::Vector2d> waypoints(const scanstop_msgs::PlanNext& srv) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : srv.response.path.poses) out.emplace_back(p.pose.position.x, p.pose.position.y);
  return out;
}
}  // namespace

TEST(ExplorerNode, PlansCollisionFreePathsFromRegisteredScans) {
  ros::NodeHandle nh;
  const test::Scene world = test::twoRooms();
  ros::Publisher pub = nh.advertise<scanstop_msgs::RegisteredScan>("slam/registered_scan", 10);
  nav_msgs::OccupancyGrid floor;
  ros::Subscriber floor_sub = nh.subscribe<nav_msgs::OccupancyGrid>(
      "explorer/floor", 1, [&](const nav_msgs::OccupancyGridConstPtr& m) { floor = *m; });
  size_t landmarks = 0;
  ros::Subscriber lm_sub = nh.subscribe<visualization_msgs::Marker>(
      "explorer/landmarks", 1, [&](const visualization_msgs::MarkerConstPtr& m) { landmarks = m->points.size(); });
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::PlanNext>("explorer/plan_next");
  ASSERT_TRUE(client.waitForExistence(ros::Duration(30.0)));
  for (int i = 0; i < 100 && pub.getNumSubscribers() == 0; ++i) ros::Duration(0.05).sleep();
  ASSERT_GT(pub.getNumSubscribers(), 0u);

  Pose2D robot(1.0, 1.0, 0.3);
  uint32_t index = 0;
  pub.publish(scanMsg(world, index, robot));
  pub.publish(scanMsg(world, index, Pose2D(7.0, 3.0, 0.0)));  // the same index again: must be ignored
  ++index;

  scanstop_msgs::PlanNext srv;
  srv.request.map_pose = ros_conv::toPoseStamped(robot, "map", ros::Time::now());
  for (int i = 0; i < 50; ++i) {  // until the scan has arrived
    ASSERT_TRUE(client.call(srv));
    if (srv.response.success) break;
    ros::Duration(0.1).sleep();
  }
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  ASSERT_FALSE(srv.response.exploration_complete) << srv.response.complete_reason;
  ASSERT_GE(srv.response.path.poses.size(), 2u);
  ASSERT_EQ(srv.response.scan_at.size(), srv.response.path.poses.size());
  EXPECT_EQ(srv.response.path.header.frame_id, "map");
  EXPECT_TRUE(srv.response.scan_at.back());
  EXPECT_GT(srv.response.score, 0.0);
  EXPECT_GT(srv.response.floor_area_m2, 5.0);
  EXPECT_LT(srv.response.floor_area_m2, 8.2 * 4.0 + 1.0);
  // The scan at (7, 3) was a duplicate index: the other room must still be unknown floor.
  EXPECT_GT(srv.response.coverage, 0.0);
  std::vector<Eigen::Vector2d> path = waypoints(srv);
  EXPECT_GE(clearance(world, path), 0.3 - 0.05) << "path collides in the true world";
  for (size_t i = 1; i < path.size(); ++i) EXPECT_LE((path[i] - path[i - 1]).norm(), 2.0 + 1e-6);

  // Follow a few plans, scanning where told: every path stays collision-free.
  for (int step = 0; step < 4; ++step) {
    for (size_t i = 1; i < path.size(); ++i)
      if (srv.response.scan_at[i]) pub.publish(scanMsg(world, index++, Pose2D(path[i].x(), path[i].y(), 0.0)));
    robot = Pose2D(path.back().x(), path.back().y(), 0.0);
    ros::Duration(0.5).sleep();
    srv.request.map_pose = ros_conv::toPoseStamped(robot, "map", ros::Time::now());
    ASSERT_TRUE(client.call(srv));
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    if (srv.response.exploration_complete) break;
    const std::vector<Eigen::Vector2d> next = waypoints(srv);
    EXPECT_GE(clearance(world, next), 0.3 - 0.05) << "step " << step;
    EXPECT_NEAR((next.front() - Eigen::Vector2d(robot.x, robot.y)).norm(), 0.0, 1e-6);
    path = next;
  }

  // A target the caller could not reach is never chosen again.
  const Eigen::Vector2d blocked(srv.response.target.pose.position.x, srv.response.target.pose.position.y);
  geometry_msgs::Point u;
  u.x = blocked.x();
  u.y = blocked.y();
  srv.request.unreachable.push_back(u);
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  if (!srv.response.exploration_complete) {
    const Eigen::Vector2d t(srv.response.target.pose.position.x, srv.response.target.pose.position.y);
    EXPECT_GT((t - blocked).norm(), 0.5);
  }

  // Grids and markers were published; the run directory holds the step images.
  for (int i = 0; i < 50 && (floor.data.empty() || landmarks == 0); ++i) {
    ros::spinOnce();
    ros::Duration(0.05).sleep();
  }
  ASSERT_FALSE(floor.data.empty());
  EXPECT_EQ(floor.data.size(), static_cast<size_t>(floor.info.width) * floor.info.height);
  EXPECT_EQ(floor.header.frame_id, "map");
  EXPECT_GT(landmarks, 0u);
  std::string run_dir;
  ASSERT_TRUE(ros::param::get("/explorer_node/run_dir", run_dir));
  EXPECT_FALSE(cv::imread(run_dir + "/step_001_evaluation.png").empty()) << run_dir;
  EXPECT_FALSE(cv::imread(run_dir + "/step_006_floor.png").empty()) << run_dir;
  if (run_dir.rfind("/tmp/explorer_rostest_run", 0) == 0) std::system(("rm -rf " + run_dir).c_str());

  // A pose in another frame is refused with a clear message.
  srv.request.map_pose.header.frame_id = "odom";
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("odom"), std::string::npos);
}

namespace {
std::string configErrorOf(const std::string& ns) {
  try {
    ExplorerNode node{ros::NodeHandle(), ros::NodeHandle(ns)};
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ExplorerNode, BadParametersStopTheNodeNamingThem) {
  ros::param::set("/bad_range/d_max_m", -1.0);
  const std::string range = configErrorOf("/bad_range");
  EXPECT_NE(range.find("d_max_m"), std::string::npos) << range;
  EXPECT_NE(range.find("-1"), std::string::npos) << range;
  ros::param::set("/bad_type/k_r_m", std::string("far"));
  const std::string type = configErrorOf("/bad_type");
  EXPECT_NE(type.find("k_r_m"), std::string::npos) << type;
  EXPECT_NE(type.find("wrong type"), std::string::npos) << type;
  ros::param::set("/bad_scale/image_scale", 99);
  const std::string scale = configErrorOf("/bad_scale");
  EXPECT_NE(scale.find("image_scale"), std::string::npos) << scale;
  ros::param::set("/good/robot_radius_m", 0.25);
  EXPECT_EQ(configErrorOf("/good"), "");
}

// The body (robot_body/..., config/robot_body.yaml, searched from the node's namespace up) gives the
// inflation and the obstacle layer's top; an explicit robot_radius_m overrides it; a bad body value
// stops the node naming the full parameter.
TEST(ExplorerNode, TheRobotBodyGivesInflationAndObstacleLayer) {
  for (const char* ns : {"/body_ns", "/no_body_ns", "/bad_body"}) ros::param::del(ns);
  ros::param::set("/body_ns/robot_body/radius", 0.35);
  ros::param::set("/body_ns/robot_body/height", 1.0);
  ros::param::set("/body_ns/explorer/inflation_margin_m", 0.05);
  ExplorerConfig c;
  NodeConfig n;
  readParameters(ros::NodeHandle("/body_ns/explorer"), c, n);
  EXPECT_NEAR(c.planner.robot_radius_m, 0.40, 1e-9);
  EXPECT_NEAR(0.5 * c.floor.floor_layer_m + c.floor.robot_height_m, 1.03, 1e-9);  // default margin 0.03
  ros::param::set("/body_ns/explorer/robot_radius_m", 0.5);
  readParameters(ros::NodeHandle("/body_ns/explorer"), c, n);
  EXPECT_NEAR(c.planner.robot_radius_m, 0.5, 1e-9);
  // No body anywhere: the built-in numbers, which equal config/robot_body.yaml's (0.26 + 0.04, top 0.63).
  ExplorerConfig d;
  readParameters(ros::NodeHandle("/no_body_ns/explorer"), d, n);
  EXPECT_NEAR(d.planner.robot_radius_m, 0.30, 1e-9);
  EXPECT_NEAR(0.5 * d.floor.floor_layer_m + d.floor.robot_height_m, 0.63, 1e-9);
  ros::param::set("/bad_body/robot_body/radius", -1.0);
  const std::string bad = configErrorOf("/bad_body/explorer");
  EXPECT_NE(bad.find("/bad_body/robot_body/radius"), std::string::npos) << bad;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "explorer_rostest");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
