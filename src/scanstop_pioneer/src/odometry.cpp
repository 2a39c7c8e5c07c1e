#include "scanstop_pioneer/odometry.h"

#include "scanstop_common/config.h"

namespace scanstop {
namespace pioneer {

void RobotParams::validate(const std::string& prefix) const {
  requireInRange(prefix + "angle_conv_rad", angle_conv_rad, 1e-5, 0.1, "rad/unit");
  requireInRange(prefix + "dist_conv_mm", dist_conv_mm, 0.01, 100.0, "mm/unit");
  requireInRange(prefix + "vel_conv", vel_conv, 0.01, 100.0);
  requireInRange(prefix + "range_conv_mm", range_conv_mm, 0.001, 100.0, "mm/unit");
  requireInRange(prefix + "diff_conv", diff_conv, 1e-4, 0.1, "1/mm");
  requireInRange(prefix + "max_velocity_mps", max_velocity_mps, 0.01, 10.0, "m/s");
  requireInRange(prefix + "max_rot_velocity_radps", max_rot_velocity_radps, 0.01, 20.0, "rad/s");
}

int wrapDelta15(uint16_t new_value, uint16_t old_value) {
  int d = static_cast<int>(new_value & 0x7FFF) - static_cast<int>(old_value & 0x7FFF);
  if (d > 0x1000)
    d -= 0x8000;
  else if (d < -0x1000)
    d += 0x8000;
  return d;
}

void OdometryIntegrator::rebase(const Pose2D& odom_pose) {
  have_last_ = false;
  pose_ = odom_pose;
  v_mps_ = w_radps_ = 0.0;
}

const Pose2D& OdometryIntegrator::update(const Sip& sip) {
  const double th = normalizeAngle(sip.th * params_.angle_conv_rad);
  if (!have_last_) {
    raw_x_m_ = sip.x * params_.dist_conv_mm * 1e-3;
    raw_y_m_ = sip.y * params_.dist_conv_mm * 1e-3;
    T_odom_raw_ = pose_ * Pose2D(raw_x_m_, raw_y_m_, th).inverse();
    have_last_ = true;
  } else {
    raw_x_m_ += wrapDelta15(sip.x, last_x_) * params_.dist_conv_mm * 1e-3;
    raw_y_m_ += wrapDelta15(sip.y, last_y_) * params_.dist_conv_mm * 1e-3;
  }
  last_x_ = sip.x;
  last_y_ = sip.y;
  pose_ = T_odom_raw_ * Pose2D(raw_x_m_, raw_y_m_, th);
  const double left = sip.left_vel * params_.vel_conv, right = sip.right_vel * params_.vel_conv;  // [mm/s]
  v_mps_ = 0.5 * (left + right) * 1e-3;
  w_radps_ = (right - left) * params_.diff_conv * 0.5;
  return pose_;
}

}  // namespace pioneer
}  // namespace scanstop
