#pragma once
/// RobotSystem over ROS services: every call waits a bounded time for the service to exist and for
/// its answer, and reports a failure in words instead of hanging.

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <mutex>
#include <optional>
#include <string>

#include "scanstop_mission/robot_system.h"

namespace scanstop {
namespace mission {

/// Time limits of the service calls [s] (wall time).
struct CallTimeouts {
  double wait_for_service_s = 30.0;  ///< how long a missing service is waited for
  double scan_s = 600.0;
  double motion_s = 120.0;
  double register_s = 120.0;
  double plan_s = 60.0;
  double mesh_s = 900.0;
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
  PlanResult planNext(const Pose2D& map_pose, const std::vector<Eigen::Vector2d>& unreachable) override;
  MeshResult buildMesh(const std::string& output_path) override;
  std::optional<Pose2D> groundTruth() override;
  int registeredScanCount() override;
  std::optional<Pose2D> registeredScanPose(int index) override;

 private:
  void onGroundTruth(const nav_msgs::Odometry::ConstPtr& msg);

  ros::NodeHandle nh_;
  CallTimeouts timeouts_;
  std::string map_dir_;
  ros::ServiceClient take_scan_, register_scan_, rotate_, forward_, plan_next_, build_mesh_;
  ros::Subscriber ground_truth_sub_;
  std::mutex mutex_;
  std::optional<Pose2D> ground_truth_;
};

}  // namespace mission
}  // namespace scanstop
