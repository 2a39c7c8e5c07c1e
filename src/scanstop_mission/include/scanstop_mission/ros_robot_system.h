#pragma once
/// RobotSystem over ROS services: every call waits a bounded time for the service to exist and for
/// its answer, and reports a failure in words instead of hanging.

#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <scanstop_msgs/MotionClearance.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_mission/robot_system.h"

namespace scanstop {
namespace mission {

/// Time limits of the service calls [s] (wall time).
struct CallTimeouts {
  double wait_for_service_timeout_s = 30.0;  ///< how long a missing service is waited for
  double scan_timeout_s = 600.0;
  double motion_timeout_s = 120.0;
  double register_timeout_s = 120.0;
  double plan_timeout_s = 60.0;
  double mesh_timeout_s = 900.0;
};

class RosRobotSystem : public RobotSystem {
 public:
  /// `nh` resolves the service and topic names (relative: scanner/take_scan, base/rotate, ...);
  /// `map_dir` is the SLAM map directory used to reconcile lost answers.
  RosRobotSystem(ros::NodeHandle& nh, const CallTimeouts& timeouts, const std::string& map_dir);

  ScanResult takeScan(int planes) override;
  RegisterResult registerScan(const ScanResult& scan) override;
  MotionResult rotate(double angle_rad) override;
  MotionResult forward(double distance_m) override;
  PlanResult planNext(const Pose2D& map_pose, const std::vector<Eigen::Vector2d>& unreachable,
                      const std::vector<Contact>& contacts, const std::optional<Eigen::Vector2d>& goal) override;
  MeshResult buildMesh(const std::string& output_path) override;
  std::optional<Pose2D> groundTruth() override;
  int registeredScanCount() override;
  std::optional<Pose2D> registeredScanPose(int index) override;
  std::vector<std::pair<int, Pose2D>> registeredScanPoses() override;
  std::optional<Pose2D> registeredScanOdometry(int index) override;
  /// The latest `odom` message (the base publishes it latched after every motion), waited for up to
  /// wait_for_service_timeout_s.
  std::optional<Pose2D> currentOdometry() override;

 private:
  void onGroundTruth(const nav_msgs::Odometry::ConstPtr& msg);
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  void onSlamPath(const nav_msgs::Path::ConstPtr& msg);
  void onClearance(const scanstop_msgs::MotionClearance::ConstPtr& msg);
  /// The true clearance of the motion that just ended (sim_node publishes it before it answers):
  /// waits up to 0.5 s for a message newer than the last one taken; nullopt without a simulator.
  std::optional<double> takeClearance();

  ros::NodeHandle nh_;
  CallTimeouts timeouts_;
  std::string map_dir_;
  ros::ServiceClient take_scan_, register_scan_, rotate_, forward_, plan_next_, build_mesh_;
  ros::Subscriber ground_truth_sub_, odom_sub_, slam_path_sub_, clearance_sub_;
  std::optional<scanstop_msgs::MotionClearance> clearance_;  ///< the newest ground_truth/clearance
  long clearance_taken_ = -1;                                ///< motion_index of the last one taken
  std::vector<Pose2D> slam_path_;  ///< scan poses from slam/path (latched): the map when map_dir is on another host
  std::mutex mutex_;
  std::optional<Pose2D> ground_truth_, odom_;
  bool mesher_seen_ = false;  ///< mesher/build_mesh existed at some point: wait for it (respawn) at the end
};

}  // namespace mission
}  // namespace scanstop
