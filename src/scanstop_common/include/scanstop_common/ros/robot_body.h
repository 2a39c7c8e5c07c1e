#pragma once
/// Reads the robot's body (config/robot_body.yaml, loaded by the launch files as robot_body/...)
/// for a node: one description for sim_node, explorer_node, mission_node and the rviz model.

#include <ros/node_handle.h>

#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/robot_body.h"
#include "scanstop_common/ros/params.h"

namespace scanstop {
namespace ros_params {

/// The body from `robot_body/...`, searched from nh's namespace upward (ros::NodeHandle::searchParam:
/// a node in a sub-namespace of the launch finds it too). Unset: RobotBody's defaults, which equal
/// config/robot_body.yaml (a test checks), and *found is false. A value of the wrong type or out of
/// range, or an unknown key under robot_body, is a ConfigError naming the full parameter.
inline RobotBody readRobotBody(const ros::NodeHandle& nh, bool* found = nullptr) {
  RobotBody body;
  std::string key;
  const bool present = nh.searchParam("robot_body", key);
  if (found) *found = present;
  if (!present) return body;
  ParamReader params(ros::NodeHandle(key), "the robot body (config/robot_body.yaml)");
  params.optional("radius", body.radius_m);
  params.optional("height", body.height_m);
  params.optional("length", body.length_m);
  params.optional("width", body.width_m);
  params.optional("body_height", body.body_height_m);
  params.optional("mast_x", body.mast_x_m);
  params.rejectUnknown();
  body.validate(key + "/");
  return body;
}

}  // namespace ros_params
}  // namespace scanstop
