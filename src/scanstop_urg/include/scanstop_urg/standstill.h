#pragma once
/// A 3D scan needs the robot standing still (thesis 3.2): rotating_urg_driver refuses a scan while
/// the base moves and discards one during which it moved. It learns the motion from the base
/// driver's odometry twist (nav_msgs/Odometry on `odom`). ROS-free checks, used by the node.

#include <string>

namespace scanstop {
namespace urg {

struct StandstillConfig {
  double max_linear_speed_mps = 0.01;     ///< [m/s] |twist.linear.x| above this: the base moves
  double max_angular_speed_radps = 0.02;  ///< [rad/s] |twist.angular.z| above this: the base moves
  /// Throws ConfigError naming the parameter (standstill/max_linear_speed, standstill/max_angular_speed).
  void validate() const;
};

/// Empty when the twist (v forward [m/s], w turn rate [rad/s]) is standing still, otherwise why
/// not, in words for the take_scan response. A non-finite twist counts as moving (it says nothing).
std::string baseMotionProblem(double v_mps, double w_radps, const StandstillConfig& config);

/// TakeScan.planes: empty when one of 50, 100, 200, 400, otherwise what is wrong.
std::string checkScanPlanes(long planes);

}  // namespace urg
}  // namespace scanstop
