#pragma once
/// Robot conversion factors and odometry from SIPs: 15-bit position wrap-around (ARIA's rule),
/// unit conversion, and the odom frame kept continuous across reconnects.

#include <cstdint>
#include <string>

#include "scanstop_common/pose.h"
#include "scanstop_pioneer/p2os_protocol.h"

namespace scanstop {
namespace pioneer {

/// Conversion factors of one robot subclass (PROTOCOL_FACTS 2.7); defaults: Pioneer 2 DX (p2dx).
struct RobotParams {
  std::string subclass = "p2dx";           ///< expected subclass from the SYNC2 reply
  double angle_conv_rad = 0.001534;        ///< [rad / angle unit] (2 pi / 4096)
  double dist_conv_mm = 0.84;              ///< [mm / position unit]
  double vel_conv = 1.0;                   ///< [mm/s per velocity unit]
  double range_conv_mm = 0.268;            ///< [mm / sonar unit]
  double diff_conv = 0.0056;               ///< [1/mm]: w [rad/s] = (right - left) [mm/s] * diff_conv / 2
  double max_velocity_mps = 2.2;           ///< [m/s] MaxVelocity
  double max_rot_velocity_radps = 8.7266;  ///< [rad/s] MaxRVelocity (500 deg/s)

  /// Throws ConfigError naming the field (prefixed by `prefix`) that is out of range.
  void validate(const std::string& prefix = "robot/") const;
};

/// The signed difference new - old of two 15-bit positions: d > 0x1000 -> d - 0x8000,
/// d < -0x1000 -> d + 0x8000 (PROTOCOL_FACTS 2.5).
int wrapDelta15(uint16_t new_value, uint16_t old_value);

/// Integrates SIP positions into an odometry pose in the odom frame [m, rad].
class OdometryIntegrator {
 public:
  explicit OdometryIntegrator(const RobotParams& params) : params_(params) {}

  /// The next SIP becomes the reference: it maps onto `odom_pose` (call after every (re)connect,
  /// so the odom frame stays continuous even when the robot's own counters restarted).
  void rebase(const Pose2D& odom_pose);
  /// Adds one SIP; returns the new odometry pose.
  const Pose2D& update(const Sip& sip);

  const Pose2D& pose() const { return pose_; }
  /// Forward speed [m/s] and turn rate [rad/s] from the last SIP's wheel velocities.
  double linearVelocity() const { return v_mps_; }
  double angularVelocity() const { return w_radps_; }
  bool hasReference() const { return have_last_; }
  const RobotParams& params() const { return params_; }

 private:
  RobotParams params_;
  bool have_last_ = false;
  uint16_t last_x_ = 0, last_y_ = 0;
  double raw_x_m_ = 0.0, raw_y_m_ = 0.0;  ///< unwrapped robot-internal position [m]
  Pose2D T_odom_raw_;                     ///< robot-internal frame in the odom frame
  Pose2D pose_;
  double v_mps_ = 0.0, w_radps_ = 0.0;
};

}  // namespace pioneer
}  // namespace scanstop
