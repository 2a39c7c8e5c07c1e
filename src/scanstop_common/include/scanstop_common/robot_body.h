#pragma once
/// The robot's body as one model (config/robot_body.yaml): the disc every node plans and checks
/// with, and the height up to which anything is an obstacle for it. ROS-free; the ROS adapter
/// (scanstop_common/ros/robot_body.h) reads it from the launch namespace.

#include <string>

namespace scanstop {

struct RobotBody {
  double radius_m = 0.26;        ///< collision disc about base_link [m], (0, 2]
  double height_m = 0.60;        ///< top of the body with the scanner mast above the floor [m], (0, 3]
  double length_m = 0.445;       ///< body box length, rviz model only [m], (0, 4]
  double width_m = 0.38;         ///< body box width, rviz model only [m], (0, 4]
  double body_height_m = 0.237;  ///< top of the body box, rviz model only [m], (0, height_m]
  double mast_x_m = 0.0;         ///< mast ahead of base_link, rviz model only [m], [-2, 2]

  /// Throws ConfigError naming the field (prefixed by `prefix`, e.g. "/robot_body/") and the range.
  void validate(const std::string& prefix = "robot_body/") const;
};

}  // namespace scanstop
