// explorer_node on scans from sim_node in room_10x8: every planned path must be collision-free in
// the true world (the simulator's obstacle map), and the robot must be able to drive it.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/PlanNext.h>
#include <scanstop_msgs/RegisteredScan.h>
#include <scanstop_msgs/Rotate.h>
#include <scanstop_msgs/TakeScan.h>

#include <cmath>
#include <cstdlib>
#include <mutex>

#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_sim/world.h"

using scanstop::Pose2D;
namespace ros_conv = scanstop::ros_conv;

namespace {
constexpr double kSimRobotRadius = 0.26;    // config/robot_body.yaml robot_body/radius
const Pose2D kStartInWorld(2.0, 5.0, 0.0);  // room_10x8's documented start pose (map = start pose)

// The latest ground truth; sim_node publishes it (latched) after every step.
std::mutex truth_mutex;
Pose2D truth_latest;
uint64_t truth_count = 0;

void onTruth(const nav_msgs::OdometryConstPtr& msg) {
  std::lock_guard<std::mutex> lock(truth_mutex);
  truth_latest = ros_conv::fromPoseMsg(msg->pose.pose);
  ++truth_count;
}

uint64_t truthCount() {
  std::lock_guard<std::mutex> lock(truth_mutex);
  return truth_count;
}

/// Calls a sim_node service and waits (wall time) for the ground truth of the new state.
template <typename Srv>
Srv call(const std::string& name, Srv srv) {
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<Srv>(name);
  EXPECT_TRUE(client.waitForExistence(ros::Duration(60.0))) << name;
  const uint64_t before = truthCount();
  EXPECT_TRUE(client.call(srv)) << name;
  for (int i = 0; i < 500 && truthCount() == before; ++i) ros::WallDuration(0.01).sleep();
  EXPECT_GT(truthCount(), before) << "no ground truth after " << name;
  return srv;
}

Pose2D groundTruth() {
  for (int i = 0; i < 1000 && truthCount() == 0; ++i) ros::WallDuration(0.01).sleep();
  EXPECT_GT(truthCount(), 0u) << "no ground truth from sim_node";
  std::lock_guard<std::mutex> lock(truth_mutex);
  return truth_latest;
}

/// Smallest true clearance [m] along a map-frame polyline.
double pathClearance(const scanstop::sim::World& world, const std::vector<Eigen::Vector2d>& path) {
  double worst = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < path.size(); ++i)
    for (int k = 0; k <= 40; ++k) {
      const Eigen::Vector2d p = path[i - 1] + (path[i] - path[i - 1]) * (k / 40.0);
      worst = std::min(worst, world.clearance(kStartInWorld.transformPoint(p)));
    }
  return worst;
}
}  // namespace

TEST(ExplorerInSim, PathsInRoom10x8AreCollisionFreeAndDrivable) {
  std::string world_file;
  ASSERT_TRUE(ros::param::get("~world", world_file));
  const scanstop::sim::World world = scanstop::sim::World::load(world_file);
  ros::NodeHandle nh;
  ros::Subscriber truth_sub = nh.subscribe("ground_truth", 10, &onTruth);
  ros::Publisher pub = nh.advertise<scanstop_msgs::RegisteredScan>("slam/registered_scan", 10);
  ros::ServiceClient planner = nh.serviceClient<scanstop_msgs::PlanNext>("explorer/plan_next");
  ASSERT_TRUE(planner.waitForExistence(ros::Duration(60.0)));
  for (int i = 0; i < 200 && pub.getNumSubscribers() == 0; ++i) ros::WallDuration(0.05).sleep();
  ASSERT_GT(pub.getNumSubscribers(), 0u);

  uint32_t index = 0;
  auto scanHere = [&]() {
    scanstop_msgs::TakeScan scan;
    scan.request.planes = 100;
    scan = call("scanner/take_scan", scan);
    ASSERT_TRUE(scan.response.success) << scan.response.message;
    const Pose2D truth = groundTruth();
    // Registered as a perfect SLAM would: the scan in the map frame at the true pose.
    const scanstop::PointCloud base = ros_conv::fromMsg(scan.response.cloud);
    scanstop::PointCloud map;
    const Eigen::Isometry3f T_map_base = truth.toIsometry3f();
    for (const auto& p : base.points)
      if (p.allFinite()) map.push_back(T_map_base * p);
    scanstop_msgs::RegisteredScan msg;
    msg.header.frame_id = "map";
    msg.header.stamp = ros::Time::now();
    msg.scan_index = index++;
    msg.pose = ros_conv::toPoseStamped(truth, "map", msg.header.stamp);
    msg.cloud = ros_conv::toMsg(map, "map", msg.header.stamp);
    msg.registration_ok = true;
    pub.publish(msg);
  };
  auto driveTo = [&](const Eigen::Vector2d& goal) {
    const Pose2D now = groundTruth();
    const Eigen::Vector2d d = goal - Eigen::Vector2d(now.x, now.y);
    if (d.norm() < 0.02) return;
    scanstop_msgs::Rotate rotate;
    rotate.request.angle_rad = scanstop::normalizeAngle(std::atan2(d.y(), d.x()) - now.yaw);
    rotate = call("base/rotate", rotate);
    ASSERT_TRUE(rotate.response.success) << rotate.response.message;
    scanstop_msgs::Forward forward;
    forward.request.distance_m = d.norm();
    forward = call("base/forward", forward);
    ASSERT_TRUE(forward.response.success) << forward.response.message;
    EXPECT_FALSE(forward.response.collision) << "collision driving to (" << goal.x() << ", " << goal.y() << ")";
  };

  scanHere();
  int plans = 0;
  double last_coverage = 0.0;
  bool complete = false;
  for (; plans < 150 && !complete; ++plans) {
    scanstop_msgs::PlanNext srv;
    srv.request.map_pose = ros_conv::toPoseStamped(groundTruth(), "map", ros::Time::now());
    // Until the explorer has the latest scan: the topic and the service race, and a plan on the map
    // before it takes another route (under load: 60 plans and 88 % coverage instead of 68 and 97 %).
    for (int attempt = 0; attempt < 100; ++attempt) {
      ASSERT_TRUE(planner.call(srv));
      if (srv.response.success && srv.response.scans == index) break;
      ros::WallDuration(0.1).sleep();
    }
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    ASSERT_EQ(srv.response.scans, index) << "the explorer did not receive the latest scan in 10 s";
    complete = srv.response.exploration_complete;
    if (complete) {
      ROS_INFO("complete after %d plans, %u scans: %s (coverage %.2f, floor %.1f m^2)", plans, index,
               srv.response.complete_reason.c_str(), srv.response.coverage, srv.response.floor_area_m2);
      last_coverage = srv.response.coverage;
      break;
    }
    std::vector<Eigen::Vector2d> path;
    for (const auto& p : srv.response.path.poses) path.emplace_back(p.pose.position.x, p.pose.position.y);
    ASSERT_GE(path.size(), 2u);
    const double clearance = pathClearance(world, path);
    EXPECT_GE(clearance, kSimRobotRadius) << "plan " << plans << " passes " << clearance << " m from an obstacle";
    for (size_t i = 1; i < path.size(); ++i) EXPECT_LE((path[i] - path[i - 1]).norm(), 2.0 + 1e-6);
    ROS_INFO("plan %d: %zu waypoints, clearance %.2f m, coverage %.2f, floor %.1f m^2", plans, path.size(), clearance,
             srv.response.coverage, srv.response.floor_area_m2);
    for (size_t i = 1; i < path.size(); ++i) {
      driveTo(path[i]);
      if (srv.response.scan_at[i]) scanHere();
    }
    last_coverage = srv.response.coverage;
  }
  EXPECT_TRUE(complete) << "not complete after " << plans << " plans";
  EXPECT_GT(plans, 5);  // the termination did not fire early
  EXPECT_GT(last_coverage, 0.9);
  std::string run_dir;
  if (ros::param::get("/explorer_node/run_dir", run_dir) && run_dir.rfind("/tmp/explorer_sim_rostest_run", 0) == 0 &&
      !std::getenv("EXPLORER_KEEP_RUN_DIR"))  // set it to page through the step images afterwards
    std::system(("rm -rf " + run_dir).c_str());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "explorer_sim_rostest");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
