#include "scanstop_common/robot_body.h"

#include "scanstop_common/config.h"

namespace scanstop {

void RobotBody::validate(const std::string& prefix) const {
  requireInRange(prefix + "radius", radius_m, 1e-3, 2.0, "m");
  requireInRange(prefix + "height", height_m, 1e-3, 3.0, "m");
  requireInRange(prefix + "length", length_m, 1e-3, 4.0, "m");
  requireInRange(prefix + "width", width_m, 1e-3, 4.0, "m");
  requireInRange(prefix + "body_height", body_height_m, 1e-3, height_m, "m");
  requireInRange(prefix + "mast_x", mast_x_m, -2.0, 2.0, "m");
}

}  // namespace scanstop
