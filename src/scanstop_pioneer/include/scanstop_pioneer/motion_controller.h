#pragma once
/// The scan-stop motion primitives of thesis 3.3: turn on the spot by an angle or drive straight by
/// a distance at a set speed, watching odometry; stop when the target is reached and report what
/// odometry measured. A stall, a bumper in the direction of motion, disabled motors or a timeout
/// abort the motion and say why. Pure logic: the driver feeds it SIP samples and sends its commands.

#include <cstdint>
#include <string>

#include "scanstop_common/pose.h"

namespace scanstop {
namespace pioneer {

struct MotionConfig {
  double linear_speed_mps = 0.2;          ///< [m/s] cruise speed of forward motions
  double angular_speed_radps = 0.35;      ///< [rad/s] cruise turn rate of rotations (20 deg/s)
  double min_linear_speed_mps = 0.03;     ///< [m/s] slowest speed of the final approach
  double min_angular_speed_radps = 0.07;  ///< [rad/s] slowest turn rate of the final approach (4 deg/s)
  double linear_decel_mps2 = 0.25;        ///< [m/s^2] slow-down profile near the target: v = sqrt(2 a d)
  double angular_decel_radps2 = 0.6;      ///< [rad/s^2] slow-down profile near the target angle
  double approach_distance_m = 0.02;      ///< [m] the last stretch is driven at min_linear_speed
  double approach_angle_rad = 0.035;      ///< [rad] the last part of a turn is at min_angular_speed
  double distance_tolerance_m = 0.005;    ///< [m] stop when this close to the distance
  double angle_tolerance_rad = 0.005;     ///< [rad] stop when this close to the angle
  double timeout_factor = 2.0;            ///< timeout = factor * nominal duration + timeout_extra_s
  double timeout_extra_s = 5.0;           ///< [s]
  double stall_time_s = 0.3;              ///< [s] a wheel stall flag lasting this long aborts
  double motors_disabled_time_s = 1.0;    ///< [s] motors reported disabled this long aborts
  double settle_timeout_s = 2.0;          ///< [s] after the stop command, wait at most this for standstill
  double max_forward_m = 5.0;             ///< [m] longest distance accepted
  double max_rotate_rad = 6.2832;         ///< [rad] largest angle accepted (2 pi)

  /// Throws ConfigError naming the field (prefixed by `prefix`) that is out of range.
  void validate(const std::string& prefix = "motion/") const;
};

/// What the robot reported at one SIP.
struct MotionSample {
  double t_s = 0.0;      ///< [s] monotonic time
  Pose2D pose;           ///< odometry pose of base_link in odom [m, rad]
  bool moving = false;   ///< SIP type 0x33
  double v_mps = 0.0;    ///< forward speed from the wheel velocities
  double w_radps = 0.0;  ///< turn rate from the wheel velocities
  bool left_stall = false, right_stall = false;
  uint8_t front_bumpers = 0, rear_bumpers = 0;
  bool motors_enabled = true;
};

/// A velocity command for the robot.
struct MotionCommand {
  double v_mps = 0.0;
  double w_radps = 0.0;
  bool stop = false;       ///< send STOP (controlled stop)
  bool emergency = false;  ///< send E_STOP (bumper)
};

enum class MotionKind { kRotate, kForward };
enum class MotionOutcome { kRunning, kReached, kStall, kBumper, kTimeout, kMotorsDisabled, kAborted };
const char* toString(MotionOutcome outcome);

class MotionController {
 public:
  /// target: [rad] (counter-clockwise positive) for kRotate, [m] (forward positive) for kForward.
  /// Throws std::invalid_argument when the target is not finite or beyond the configured limit.
  MotionController(const MotionConfig& config, MotionKind kind, double target, const MotionSample& start);

  /// Feeds the next sample; returns the command to send now.
  MotionCommand update(const MotionSample& sample);
  /// Ends the motion at once from outside (link lost, shutdown): no further samples will come.
  void abort(const std::string& reason, double t_s);

  bool finished() const { return phase_ == Phase::kDone; }
  MotionOutcome outcome() const { return outcome_; }
  bool success() const { return outcome_ == MotionOutcome::kReached; }
  /// The motion ended on a stall or bumper (the robot touched something).
  bool collision() const { return outcome_ == MotionOutcome::kStall || outcome_ == MotionOutcome::kBumper; }
  /// [rad] or [m]: the rotation (unwrapped) or the signed straight-line distance from the start
  /// measured by odometry, including any overshoot while stopping.
  double achieved() const { return achieved_; }
  double durationS() const { return end_t_ - start_.t_s; }
  const Pose2D& lastPose() const { return last_.pose; }
  const std::string& message() const { return message_; }
  /// The nominal timeout of this motion [s].
  double timeoutS() const { return timeout_s_; }

 private:
  enum class Phase { kDriving, kStopping, kDone };
  void beginStop(MotionOutcome outcome, const std::string& message, double t_s);
  void finish(double t_s);
  std::string unit(double value) const;

  MotionConfig config_;
  MotionKind kind_;
  double target_;
  MotionSample start_, last_;
  Phase phase_ = Phase::kDriving;
  MotionOutcome outcome_ = MotionOutcome::kRunning;
  std::string message_;
  double achieved_ = 0.0;
  double timeout_s_ = 0.0;
  double stall_since_ = -1.0, disabled_since_ = -1.0, stop_t_ = 0.0, end_t_ = 0.0;
};

}  // namespace pioneer
}  // namespace scanstop
