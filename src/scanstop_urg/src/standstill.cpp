#include "scanstop_urg/standstill.h"

#include <cmath>
#include <cstdio>

#include "scanstop_common/config.h"

namespace scanstop {
namespace urg {

void StandstillConfig::validate() const {
  requireInRange("standstill/max_linear_speed_mps", max_linear_speed_mps, 0.0, 0.5, "m/s");
  requireInRange("standstill/max_angular_speed_radps", max_angular_speed_radps, 0.0, 1.0, "rad/s");
}

std::string baseMotionProblem(double v_mps, double w_radps, const StandstillConfig& config) {
  const bool still =
      std::abs(v_mps) <= config.max_linear_speed_mps && std::abs(w_radps) <= config.max_angular_speed_radps;
  if (still) return "";  // (false for NaN: a non-finite twist counts as moving)
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "the base is moving (odometry twist v = %.3g m/s, w = %.3g rad/s; standing still means "
                "|v| <= %.3g m/s and |w| <= %.3g rad/s): a scan needs the robot standing still",
                v_mps, w_radps, config.max_linear_speed_mps, config.max_angular_speed_radps);
  return buf;
}

std::string checkScanPlanes(long planes) {
  if (planes == 50 || planes == 100 || planes == 200 || planes == 400) return "";
  return "planes = " + std::to_string(planes) + " is not one of 50, 100, 200, 400";
}

}  // namespace urg
}  // namespace scanstop
