// rostest of sim_node's wiring: a client takes a scan, rotates, drives, scans again, and drives into
// a wall; it checks the cloud layout and frames, odometry against ground truth, and the collision.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/MotionClearance.h>
#include <scanstop_msgs/ResetSim.h>
#include <scanstop_msgs/Rotate.h>
#include <scanstop_msgs/TakeScan.h>
#include <tf2_ros/transform_listener.h>

#include <array>
#include <cmath>
#include <future>
#include <mutex>
#include <utility>
#include <vector>

#include "scanstop_common/ros/msg_conversion.h"

namespace {

using scanstop::Pose2D;

template <typename Srv>
Srv call(const std::string& name, Srv srv) {
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<Srv>(name);
  EXPECT_TRUE(client.waitForExistence(ros::Duration(30.0))) << name;
  EXPECT_TRUE(client.call(srv)) << name;
  return srv;
}

Pose2D groundTruth() {
  const auto msg = ros::topic::waitForMessage<nav_msgs::Odometry>("ground_truth", ros::Duration(5.0));
  EXPECT_TRUE(msg != nullptr);
  EXPECT_EQ(msg->header.frame_id, "map");
  return msg ? scanstop::ros_conv::fromPoseMsg(msg->pose.pose) : Pose2D();
}

TEST(SimNode, ScanRotateForwardScanAndCollide) {
  // Listen to tf from the start: odom -> base_link is sent at every step (simulated time stands
  // still between steps).
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ros::NodeHandle nh;
  while (nh.resolveName("tf").empty() ||
         ros::topic::waitForMessage<nav_msgs::Odometry>("ground_truth", ros::Duration(1.0)) == nullptr)
    ros::WallDuration(0.1).sleep();
  ros::WallDuration(1.0).sleep();  // let the tf subscription connect before the first step
  scanstop_msgs::TakeScan scan;
  scan.request.planes = 100;
  scan = call("scanner/take_scan", scan);
  ASSERT_TRUE(scan.response.success) << scan.response.message;
  EXPECT_EQ(scan.response.cloud.height, 100u);
  EXPECT_EQ(scan.response.cloud.width, 682u);
  EXPECT_FALSE(scan.response.cloud.is_dense);
  EXPECT_EQ(scan.response.cloud.header.frame_id, "base_link");
  EXPECT_EQ(scan.response.odom_pose.header.frame_id, "odom");
  EXPECT_EQ(scan.response.counts.raw_points, 68200u);
  EXPECT_GT(scan.response.counts.valid_points, 40000u);
  EXPECT_DOUBLE_EQ(scan.response.duration_s, 10.0);
  const scanstop::PointCloud cloud = scanstop::ros_conv::fromMsg(scan.response.cloud);
  EXPECT_EQ(cloud.countFinite(), scan.response.counts.valid_points);

  scanstop_msgs::Rotate rotate;
  rotate.request.angle_rad = M_PI / 2;
  rotate = call("base/rotate", rotate);
  ASSERT_TRUE(rotate.response.success);
  EXPECT_DOUBLE_EQ(rotate.response.achieved_angle_rad, M_PI / 2);

  scanstop_msgs::Forward forward;
  forward.request.distance_m = 1.5;
  forward = call("base/forward", forward);
  ASSERT_TRUE(forward.response.success);
  EXPECT_FALSE(forward.response.collision);
  // The perfect profile: odometry equals ground truth (both relative to the start pose).
  const Pose2D odom = scanstop::ros_conv::fromPoseMsg(forward.response.odom_pose.pose);
  const Pose2D truth = groundTruth();
  EXPECT_NEAR(odom.x, 0.0, 1e-9);
  EXPECT_NEAR(odom.y, 1.5, 1e-9);
  EXPECT_NEAR(truth.x, odom.x, 1e-6);
  EXPECT_NEAR(truth.y, odom.y, 1e-6);
  EXPECT_NEAR(truth.yaw, odom.yaw, 1e-6);

  // tf odom -> base_link matches the odometry at the current (simulated) time.
  ros::WallDuration(0.5).sleep();
  const auto tf = buffer.lookupTransform("odom", "base_link", ros::Time(0));
  EXPECT_NEAR(tf.transform.translation.y, 1.5, 1e-6);
  const auto laser = buffer.lookupTransform("base_link", "laser", ros::Time(0));
  EXPECT_NEAR(laser.transform.translation.z, 0.45, 1e-9);

  scan = call("scanner/take_scan", scan);
  ASSERT_TRUE(scan.response.success);

  // Turn west and drive 3 m: at y = 6.5 the cabinet along the west wall (front face x = 0.55) is
  // 2.0 - 0.55 m ahead; the robot (radius 0.26 m) stops at contact.
  rotate.request.angle_rad = M_PI / 2;
  ASSERT_TRUE(call("base/rotate", rotate).response.success);
  forward.request.distance_m = 3.0;
  // Every motion's true clearance is published before the call is answered: this one ends in contact.
  std::vector<scanstop_msgs::MotionClearance> clearances;
  std::mutex clearance_mutex;
  ros::Subscriber clearance_sub = nh.subscribe<scanstop_msgs::MotionClearance>(
      "ground_truth/clearance", 10, [&](const scanstop_msgs::MotionClearance::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(clearance_mutex);
        clearances.push_back(*m);
      });
  for (int i = 0; i < 100 && clearance_sub.getNumPublishers() == 0; ++i) ros::WallDuration(0.05).sleep();
  forward = call("base/forward", forward);
  const auto received = [&] {
    std::lock_guard<std::mutex> lock(clearance_mutex);
    return clearances.size();
  };
  for (int i = 0; i < 100 && received() == 0; ++i) ros::WallDuration(0.01).sleep();
  {
    std::lock_guard<std::mutex> lock(clearance_mutex);
    ASSERT_EQ(clearances.size(), 1u);
    EXPECT_EQ(clearances[0].motion, "forward");
    EXPECT_DOUBLE_EQ(clearances[0].command, 3.0);
    EXPECT_TRUE(clearances[0].collision);
    EXPECT_EQ(clearances[0].min_clearance_m, 0.0);
  }
  clearance_sub.shutdown();
  EXPECT_TRUE(forward.response.collision);
  EXPECT_FALSE(forward.response.success);
  EXPECT_NE(forward.response.message.find("collision"), std::string::npos);
  EXPECT_NEAR(forward.response.achieved_distance_m, 2.0 - 0.55 - 0.26, 0.011);
  EXPECT_GT(groundTruth().x + 2.0, 0.55 + 0.26 - 1e-6);  // never inside the cabinet (world x = 2 + map x)

  // Absurd requests are refused with a reason, nothing moves.
  forward.request.distance_m = 100.0;
  forward = call("base/forward", forward);
  EXPECT_FALSE(forward.response.success);
  EXPECT_NE(forward.response.message.find("max_forward"), std::string::npos);
  scan.request.planes = 123;
  EXPECT_FALSE(call("scanner/take_scan", scan).response.success);
}

TEST(SimNode, LateTfSubscriberGetsTheCurrentPose) {
  // Runs after the steps above. A tf listener started now (rviz, a late node) receives the current
  // odom -> base_link on connecting; with odom_as_map (map -> odom identity) and the perfect
  // profile, map -> base_link is the ground truth.
  const Pose2D truth = groundTruth();
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (!buffer.canTransform("world", "base_link", ros::Time(0)) && ros::WallTime::now() < deadline)
    ros::WallDuration(0.1).sleep();
  ASSERT_TRUE(buffer.canTransform("world", "base_link", ros::Time(0))) << "no world -> base_link for a late listener";
  const Pose2D in_map = scanstop::ros_conv::fromPoseMsg([&] {
    const auto t = buffer.lookupTransform("map", "base_link", ros::Time(0)).transform;
    geometry_msgs::Pose p;
    p.position.x = t.translation.x;
    p.position.y = t.translation.y;
    p.position.z = t.translation.z;
    p.orientation = t.rotation;
    return p;
  }());
  EXPECT_NEAR(in_map.x, truth.x, 1e-6);
  EXPECT_NEAR(in_map.y, truth.y, 1e-6);
  EXPECT_NEAR(std::remainder(in_map.yaw - truth.yaw, 2 * M_PI), 0.0, 1e-6);
  // world -> map is the start pose of room_10x8 (2, 5, 0).
  const auto world_map = buffer.lookupTransform("world", "map", ros::Time(0)).transform;
  EXPECT_NEAR(world_map.translation.x, 2.0, 1e-9);
  EXPECT_NEAR(world_map.translation.y, 5.0, 1e-9);
}

/// The robot's state as the node publishes it: ground truth (map frame) and odometry.
std::pair<Pose2D, Pose2D> robotState() {
  const auto odom = ros::topic::waitForMessage<nav_msgs::Odometry>("odom", ros::Duration(5.0));
  EXPECT_TRUE(odom != nullptr);
  return {groundTruth(), odom ? scanstop::ros_conv::fromPoseMsg(odom->pose.pose) : Pose2D()};
}

void expectUnchanged(const std::pair<Pose2D, Pose2D>& before, const std::string& what) {
  const auto after = robotState();
  EXPECT_EQ(after.first.toString(), before.first.toString()) << "ground truth changed by " << what;
  EXPECT_EQ(after.second.toString(), before.second.toString()) << "odometry changed by " << what;
}

TEST(SimNode, BadRequestsAreRefusedAndChangeNothing) {
  const auto before = robotState();
  scanstop_msgs::Forward forward;
  for (double d : {100.0, -100.0, std::nan(""), double(INFINITY)}) {
    forward.request.distance_m = d;
    forward = call("base/forward", forward);
    EXPECT_FALSE(forward.response.success) << d;
    EXPECT_NE(forward.response.message.find("distance_m"), std::string::npos) << forward.response.message;
    EXPECT_NE(forward.response.message.find("max_forward"), std::string::npos) << forward.response.message;
    expectUnchanged(before, "forward " + std::to_string(d));
  }
  scanstop_msgs::Rotate rotate;
  for (double a : {50.0, -7.0, std::nan(""), -double(INFINITY)}) {
    rotate.request.angle_rad = a;
    rotate = call("base/rotate", rotate);
    EXPECT_FALSE(rotate.response.success) << a;
    EXPECT_NE(rotate.response.message.find("angle_rad"), std::string::npos) << rotate.response.message;
    EXPECT_NE(rotate.response.message.find("max_rotate"), std::string::npos) << rotate.response.message;
    expectUnchanged(before, "rotate " + std::to_string(a));
  }
  scanstop_msgs::TakeScan scan;
  for (int planes : {0, 1, 123, 401}) {
    scan.request.planes = static_cast<uint16_t>(planes);
    scan = call("scanner/take_scan", scan);
    EXPECT_FALSE(scan.response.success);
    EXPECT_NE(scan.response.message.find("planes = " + std::to_string(planes)), std::string::npos)
        << scan.response.message;
    EXPECT_EQ(scan.response.cloud.data.size(), 0u);
  }
  scanstop_msgs::ResetSim reset;
  const std::vector<std::pair<std::array<double, 3>, std::string>> poses{{{std::nan(""), 5.0, 0.0}, "not finite"},
                                                                         {{1000.0, 5.0, 0.0}, "outside the world"},
                                                                         {{2.0, 5.0, 50.0}, "theta = 50"},
                                                                         {{0.05, 5.0, 0.0}, "puts the robot"}};
  for (const auto& p : poses) {
    reset.request.pose.x = p.first[0];
    reset.request.pose.y = p.first[1];
    reset.request.pose.theta = p.first[2];
    reset.request.seed = 3;
    reset = call("sim/reset", reset);
    EXPECT_FALSE(reset.response.success);
    EXPECT_NE(reset.response.message.find(p.second), std::string::npos) << reset.response.message;
    expectUnchanged(before, "reset " + reset.response.message);
  }
}

TEST(SimNode, ScanIsRefusedWhileTheBaseMoves) {
  // Back at the start (room_10x8: world 2, 5) facing north, where 1.5 m ahead is free.
  scanstop_msgs::ResetSim reset;
  reset.request.pose.x = 2.0;
  reset.request.pose.y = 5.0;
  reset.request.pose.theta = M_PI / 2;
  reset.request.seed = -1;
  reset = call("sim/reset", reset);
  ASSERT_TRUE(reset.response.success) << reset.response.message;
  // motion_time_scale 0.2 (sim.test): 1.5 m at 0.2 m/s take 7.5 s modelled, 1.5 s on the wall clock.
  scanstop_msgs::Forward forward;
  forward.request.distance_m = 1.5;
  auto motion = std::async(std::launch::async, [forward] { return call("base/forward", forward); });
  // odom shows the motion while it runs.
  nav_msgs::Odometry::ConstPtr odom;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(1.0);
  while (ros::WallTime::now() < deadline) {
    odom = ros::topic::waitForMessage<nav_msgs::Odometry>("odom", ros::Duration(0.2));
    if (odom && odom->twist.twist.linear.x > 0.0) break;
  }
  ASSERT_TRUE(odom != nullptr);
  EXPECT_NEAR(odom->twist.twist.linear.x, 0.2, 1e-9);
  scanstop_msgs::TakeScan scan;
  scan.request.planes = 50;
  const ros::WallTime asked = ros::WallTime::now();
  scan = call("scanner/take_scan", scan);
  EXPECT_FALSE(scan.response.success);
  EXPECT_NE(scan.response.message.find("the base is moving"), std::string::npos) << scan.response.message;
  EXPECT_LT((ros::WallTime::now() - asked).toSec(), 0.5) << "the refusal must not wait for the motion";
  // A second motion meanwhile is refused as well, a reset too.
  scanstop_msgs::Rotate rotate;
  rotate.request.angle_rad = 1.0;
  rotate = call("base/rotate", rotate);
  EXPECT_FALSE(rotate.response.success);
  EXPECT_NE(rotate.response.message.find("another rotate/forward motion"), std::string::npos)
      << rotate.response.message;
  reset.request.pose.theta = 0.0;
  EXPECT_FALSE(call("sim/reset", reset).response.success);
  const scanstop_msgs::Forward done = motion.get();
  EXPECT_TRUE(done.response.success) << done.response.message;
  EXPECT_NEAR(done.response.achieved_distance_m, 1.5, 1e-9);
  EXPECT_NEAR(scanstop::ros_conv::fromPoseMsg(done.response.odom_pose.pose).x, 1.5,
              1e-9);  // odometry restarted at the reset
  // Standing again: odom at rest, the scan works.
  const auto rest = ros::topic::waitForMessage<nav_msgs::Odometry>("odom", ros::Duration(5.0));
  ASSERT_TRUE(rest != nullptr);
  EXPECT_EQ(rest->twist.twist.linear.x, 0.0);
  scan = call("scanner/take_scan", scan);
  EXPECT_TRUE(scan.response.success) << scan.response.message;
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "sim_rostest");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
