#pragma once
/// rotating_urg_driver wires the UrgDriver to ROS: the scanner/take_scan service (the same as
/// sim_node's), scanner/last_scan, scanner/progress, the static base_link -> laser transform,
/// diagnostics and the reconnect timer.

#include <diagnostic_updater/diagnostic_updater.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <scanstop_msgs/TakeScan.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <string>

#include "scanstop_common/ros/params.h"
#include "scanstop_urg/driver.h"
#include "scanstop_urg/standstill.h"

namespace scanstop {
namespace urg {

/// Reads every parameter of the node (see README) into a DriverConfig; throws ConfigError naming
/// the parameter that is wrong.
DriverConfig readDriverConfig(ros_params::ParamReader& params);
/// Reads standstill/max_linear_speed and standstill/max_angular_speed; throws ConfigError.
StandstillConfig readStandstillConfig(ros_params::ParamReader& params);
/// The node's own parameters (topics, timers, frames; see README); throws ConfigError.
struct NodeParameters {
  std::string odom_topic = "odom";
  double reconnect_interval_s = 1.0, diagnostic_period_s = 1.0, odom_timeout_s = 0.5;
  bool require_odom = true;
  std::string base_frame = "base_link", laser_frame = "laser", odom_frame = "odom";
};
NodeParameters readNodeParameters(ros_params::ParamReader& params);

class UrgDriverNode {
 public:
  /// Reads and validates the parameters; throws ConfigError. The device may be absent: the node
  /// keeps trying to connect.
  UrgDriverNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);

 private:
  bool onTakeScan(scanstop_msgs::TakeScan::Request& req, scanstop_msgs::TakeScan::Response& res);
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg);
  void onReconnectTimer(const ros::WallTimerEvent&);
  void onDiagnosticsTimer(const ros::WallTimerEvent&);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  /// The odometry pose of base_link now; false (with `error`) when tf does not have it.
  bool odomPose(geometry_msgs::PoseStamped* pose, std::string* error);

  std::unique_ptr<UrgDriver> driver_;
  std::mutex device_mutex_;  ///< one scan or connection attempt at a time
  std::string base_frame_ = "base_link", laser_frame_ = "laser", odom_frame_ = "odom";
  double odom_timeout_s_ = 0.5;
  bool require_odom_ = true;
  bool was_connected_ = false;
  StandstillConfig standstill_;
  std::mutex odom_mutex_;    ///< guards the three below
  std::string base_motion_;  ///< why the base moves now (last odom twist); empty: standing still
  bool scanning_ = false;
  std::string moved_during_scan_;  ///< the first motion seen while scanning
  ros::Subscriber odom_sub_;
  ros::ServiceServer take_scan_srv_;
  ros::Publisher scan_pub_, progress_pub_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer reconnect_timer_, diagnostics_timer_;
};

}  // namespace urg
}  // namespace scanstop
