#pragma once
/// pioneer_driver wires the PioneerDriver core to ROS: base/rotate and base/forward (the same
/// services as sim_node), odom + tf odom -> base_link from every accepted SIP, battery, stall and
/// bumper state, diagnostics, and cmd_vel teleoperation with a command timeout.

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/Rotate.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <string>
#include <vector>

#include "scanstop_common/ros/params.h"
#include "scanstop_pioneer/pioneer_driver.h"

namespace scanstop {
namespace pioneer {

class PioneerDriverNode {
 public:
  /// Reads and validates the parameters (ConfigError naming the parameter) and starts the driver.
  PioneerDriverNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  ~PioneerDriverNode();

  /// Every private parameter of the node (defaults = the structs' defaults), validated (ConfigError
  /// naming the parameter); params.unknown() then lists what nothing read.
  struct Parameters {
    DriverConfig driver;
    std::string odom_frame = "odom", base_frame = "base_link";
    bool publish_tf = true;
  };
  static Parameters readParameters(ros_params::ParamReader& params);
  /// The master watchdog's handlers: stop the robot and refuse motions while the ROS master is gone
  /// (nobody supervises the robot), accept them again when it is back.
  void onMasterLost(const std::string& why);
  void onMasterBack();

 private:
  void onSip(const DriverStatus& status);
  void onCmdVel(const geometry_msgs::Twist::ConstPtr& msg);
  bool onRotate(scanstop_msgs::Rotate::Request& req, scanstop_msgs::Rotate::Response& res);
  bool onForward(scanstop_msgs::Forward::Request& req, scanstop_msgs::Forward::Response& res);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void onTimer(const ros::WallTimerEvent&);

  std::unique_ptr<PioneerDriver> driver_;
  std::string odom_frame_ = "odom", base_frame_ = "base_link";
  bool publish_tf_ = true;
  ros::Publisher odom_pub_, battery_pub_, stall_pub_, bumper_pub_;
  ros::Subscriber cmd_vel_sub_;
  ros::ServiceServer rotate_srv_, forward_srv_;
  tf2_ros::TransformBroadcaster tf_;
  diagnostic_updater::Updater updater_;
  ros::WallTimer timer_;
  uint64_t rate_sips_ = 0;    ///< SIP count at the last timer tick
  ros::WallTime rate_time_;   ///< time of the last timer tick
  double sip_rate_hz_ = 0.0;  ///< accepted SIPs per second over the last tick
};

}  // namespace pioneer
}  // namespace scanstop
