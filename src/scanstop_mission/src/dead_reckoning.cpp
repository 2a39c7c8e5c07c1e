#include "scanstop_mission/dead_reckoning.h"

#include <algorithm>
#include <cmath>

namespace scanstop {
namespace mission {

void DeadReckoning::reset() {
  driven_m_ = 0.0;
  turned_rad_ = 0.0;
  position_m_ = 0.0;
}

double DeadReckoning::headingBoundRad() const {
  return std::min(kMaxHeadingRad, model_.turn_error * turned_rad_ + model_.drift_rad_per_m * driven_m_);
}

void DeadReckoning::add(const Pose2D& delta) {
  const double d = std::hypot(delta.x, delta.y);
  if (d > 0.0) {
    // The heading bound grows along the motion by the drift: the lateral error is its integral.
    const double h0 = headingBoundRad();
    const double h1 = std::min(kMaxHeadingRad, h0 + model_.drift_rad_per_m * d);
    position_m_ += d * std::tan(0.5 * (h0 + h1)) + model_.distance_error * d;
    driven_m_ += d;
  }
  const double turn = std::abs(normalizeAngle(delta.yaw));
  turned_rad_ += turn;
  position_m_ += model_.turn_position_m_per_rad * turn;
}

double DeadReckoning::widenedRadius(double radius_m, double ahead_m) const {
  const double ahead = std::max(0.0, ahead_m);
  const double heading = std::min(kMaxHeadingRad, headingBoundRad() + 0.5 * model_.drift_rad_per_m * ahead);
  return radius_m + position_m_ + ahead * std::tan(heading);
}

}  // namespace mission
}  // namespace scanstop
