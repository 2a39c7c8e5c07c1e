#include "scanstop_pioneer/motion_controller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "scanstop_common/config.h"

namespace scanstop {
namespace pioneer {
namespace {

std::string fmt(double v, int digits = 3) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

void MotionConfig::validate(const std::string& p) const {
  requireInRange(p + "linear_speed_mps", linear_speed_mps, 0.01, 1.5, "m/s");
  requireInRange(p + "angular_speed_radps", angular_speed_radps, 0.02, 3.0, "rad/s");
  requireInRange(p + "min_linear_speed_mps", min_linear_speed_mps, 0.001, linear_speed_mps, "m/s");
  requireInRange(p + "min_angular_speed_radps", min_angular_speed_radps, 0.0175, angular_speed_radps, "rad/s");
  requirePositive(p + "linear_decel_mps2", linear_decel_mps2, "m/s^2");
  requirePositive(p + "angular_decel_radps2", angular_decel_radps2, "rad/s^2");
  requireInRange(p + "approach_distance_m", approach_distance_m, 0.0, 1.0, "m");
  requireInRange(p + "approach_angle_rad", approach_angle_rad, 0.0, 1.0, "rad");
  requireInRange(p + "distance_tolerance_m", distance_tolerance_m, 0.0, 0.5, "m");
  requireInRange(p + "angle_tolerance_rad", angle_tolerance_rad, 0.0, 0.5, "rad");
  requireInRange(p + "timeout_factor", timeout_factor, 1.0, 100.0);
  requireInRange(p + "timeout_extra_s", timeout_extra_s, 0.0, 600.0, "s");
  requireInRange(p + "stall_time_s", stall_time_s, 0.0, 10.0, "s");
  requireInRange(p + "motors_disabled_time_s", motors_disabled_time_s, 0.0, 10.0, "s");
  requireInRange(p + "settle_timeout_s", settle_timeout_s, 0.1, 30.0, "s");
  requireInRange(p + "max_forward_m", max_forward_m, 0.01, 100.0, "m");
  requireInRange(p + "max_rotate_rad", max_rotate_rad, 0.01, 4.0 * M_PI, "rad");
}

const char* toString(MotionOutcome outcome) {
  switch (outcome) {
    case MotionOutcome::kRunning:
      return "running";
    case MotionOutcome::kReached:
      return "reached";
    case MotionOutcome::kStall:
      return "stall";
    case MotionOutcome::kBumper:
      return "bumper";
    case MotionOutcome::kTimeout:
      return "timeout";
    case MotionOutcome::kMotorsDisabled:
      return "motors disabled";
    case MotionOutcome::kAborted:
      return "aborted";
  }
  return "?";
}

MotionController::MotionController(const MotionConfig& config, MotionKind kind, double target,
                                   const MotionSample& start)
    : config_(config), kind_(kind), target_(target), start_(start), last_(start), end_t_(start.t_s) {
  const double limit = kind == MotionKind::kRotate ? config.max_rotate_rad : config.max_forward_m;
  const char* name = kind == MotionKind::kRotate ? "angle_rad" : "distance_m";
  if (!std::isfinite(target) || std::abs(target) > limit)
    throw std::invalid_argument(std::string(name) + " = " + fmt(target) + " must be finite and within [-" + fmt(limit) +
                                ", " + fmt(limit) + "]");
  const double speed = kind == MotionKind::kRotate ? config.angular_speed_radps : config.linear_speed_mps;
  const double decel = kind == MotionKind::kRotate ? config.angular_decel_radps2 : config.linear_decel_mps2;
  const double min_speed = kind == MotionKind::kRotate ? config.min_angular_speed_radps : config.min_linear_speed_mps;
  const double approach = kind == MotionKind::kRotate ? config.approach_angle_rad : config.approach_distance_m;
  const double nominal = std::abs(target) / speed + speed / decel + std::min(std::abs(target), approach) / min_speed;
  timeout_s_ = config.timeout_factor * nominal + config.timeout_extra_s;
  const double tol = kind == MotionKind::kRotate ? config.angle_tolerance_rad : config.distance_tolerance_m;
  if (std::abs(target) <= tol) {
    outcome_ = MotionOutcome::kReached;
    message_ = "already within the tolerance of " + unit(tol) + ": nothing to do";
    finish(start.t_s);
  }
}

std::string MotionController::unit(double value) const {
  return fmt(value) + (kind_ == MotionKind::kRotate ? " rad" : " m");
}

void MotionController::beginStop(MotionOutcome outcome, const std::string& message, double t_s) {
  outcome_ = outcome;
  message_ = message;
  phase_ = Phase::kStopping;
  stop_t_ = t_s;
}

void MotionController::finish(double t_s) {
  phase_ = Phase::kDone;
  end_t_ = t_s;
  if (outcome_ == MotionOutcome::kReached && message_.empty())
    message_ = std::string(kind_ == MotionKind::kRotate ? "rotated " : "drove ") + unit(achieved_) + " (requested " +
               unit(target_) + ")";
}

void MotionController::abort(const std::string& reason, double t_s) {
  if (phase_ == Phase::kDone) return;
  if (phase_ == Phase::kDriving || outcome_ == MotionOutcome::kReached) {
    outcome_ = MotionOutcome::kAborted;
    message_ = reason + " after " + unit(achieved_) + " of " + unit(target_);
  } else {
    message_ += "; then " + reason;
  }
  finish(t_s);
}

MotionCommand MotionController::update(const MotionSample& s) {
  MotionCommand command;
  if (phase_ == Phase::kDone) {
    command.stop = true;
    return command;
  }
  // Progress from odometry.
  if (kind_ == MotionKind::kRotate) {
    achieved_ += normalizeAngle(s.pose.yaw - last_.pose.yaw);
  } else {
    const double dx = s.pose.x - start_.pose.x, dy = s.pose.y - start_.pose.y;
    const double along = dx * std::cos(start_.pose.yaw) + dy * std::sin(start_.pose.yaw);
    achieved_ = (along < 0.0 ? -1.0 : 1.0) * std::hypot(dx, dy);
  }
  last_ = s;
  const double sign = target_ < 0.0 ? -1.0 : 1.0;
  const double remaining = std::abs(target_) - sign * achieved_;
  const double elapsed = s.t_s - start_.t_s;

  if (phase_ == Phase::kDriving) {
    const bool left = s.left_stall, right = s.right_stall;
    if (left || right) {
      if (stall_since_ < 0.0) stall_since_ = s.t_s;
    } else {
      stall_since_ = -1.0;
    }
    disabled_since_ = s.motors_enabled ? -1.0 : (disabled_since_ < 0.0 ? s.t_s : disabled_since_);
    uint8_t bumpers = 0;
    const char* side = "";
    if (kind_ == MotionKind::kRotate) {
      bumpers = s.front_bumpers | s.rear_bumpers;
      side = s.front_bumpers ? "front" : "rear";
    } else {
      bumpers = target_ > 0.0 ? s.front_bumpers : s.rear_bumpers;
      side = target_ > 0.0 ? "front" : "rear";
    }
    if (bumpers != 0) {
      char bits[8];
      std::snprintf(bits, sizeof(bits), "0x%02X", bumpers);
      beginStop(MotionOutcome::kBumper,
                std::string(side) + " bumper pressed (bits " + bits + ") after " + unit(achieved_) + " of " +
                    unit(target_) + ": the robot touched an obstacle",
                s.t_s);
      command.stop = command.emergency = true;
      return command;
    }
    if (stall_since_ >= 0.0 && s.t_s - stall_since_ >= config_.stall_time_s) {
      const std::string wheels = left && right ? "both wheels" : (left ? "left wheel" : "right wheel");
      beginStop(
          MotionOutcome::kStall,
          "stall: " + wheels + " stalled after " + unit(achieved_) + " of " + unit(target_) + ": the robot is blocked",
          s.t_s);
      command.stop = true;
      return command;
    }
    if (disabled_since_ >= 0.0 && s.t_s - disabled_since_ >= config_.motors_disabled_time_s) {
      beginStop(MotionOutcome::kMotorsDisabled,
                "the robot reports its motors disabled (motor switch off or ENABLE refused) after " + unit(achieved_) +
                    " of " + unit(target_),
                s.t_s);
      command.stop = true;
      return command;
    }
    if (remaining <= (kind_ == MotionKind::kRotate ? config_.angle_tolerance_rad : config_.distance_tolerance_m)) {
      beginStop(MotionOutcome::kReached, "", s.t_s);
      command.stop = true;
      return command;
    }
    if (elapsed > timeout_s_) {
      beginStop(MotionOutcome::kTimeout,
                "timeout: " + unit(achieved_) + " of " + unit(target_) + " reached in " + fmt(elapsed, 1) +
                    " s (limit " + fmt(timeout_s_, 1) + " s); odometry is not advancing as commanded",
                s.t_s);
      command.stop = true;
      return command;
    }
    if (kind_ == MotionKind::kRotate) {
      // Slow down as sqrt(2 a d) so that the robot arrives at the approach zone at the minimum
      // speed, then creep: the overshoot after the stop command stays small despite SIP latency.
      const double d = std::max(0.0, remaining - config_.approach_angle_rad);
      const double w = std::clamp(std::sqrt(2.0 * config_.angular_decel_radps2 * d), config_.min_angular_speed_radps,
                                  config_.angular_speed_radps);
      command.w_radps = sign * w;
    } else {
      const double d = std::max(0.0, remaining - config_.approach_distance_m);
      const double v = std::clamp(std::sqrt(2.0 * config_.linear_decel_mps2 * d), config_.min_linear_speed_mps,
                                  config_.linear_speed_mps);
      command.v_mps = sign * v;
    }
    return command;
  }

  // Stopping: wait for standstill (SIP type 0x32 and no wheel motion) or the settle timeout.
  command.stop = true;
  const bool still = !s.moving && std::abs(s.v_mps) < 1e-3 && std::abs(s.w_radps) < 1e-3;
  if (still || s.t_s - stop_t_ >= config_.settle_timeout_s) {
    if (!still && outcome_ == MotionOutcome::kReached)
      message_ = "target reached but the robot still reported motion " + fmt(config_.settle_timeout_s, 1) +
                 " s after the stop command";
    finish(s.t_s);
  }
  return command;
}

}  // namespace pioneer
}  // namespace scanstop
