#pragma once
/// Parameter reading for nodes: a missing required parameter or a value of the wrong type is an
/// error naming the parameter (with its full namespace), never a silent default.

#include <ros/node_handle.h>

#include <string>

#include "scanstop_common/error.h"

namespace scanstop {
namespace ros_params {

/// Reads a required parameter; throws ConfigError when it is missing or of the wrong type.
template <typename T>
T require(const ros::NodeHandle& nh, const std::string& name) {
  T value;
  if (!nh.hasParam(name)) throw ConfigError("required parameter '" + nh.resolveName(name) + "' is not set");
  if (!nh.getParam(name, value))
    throw ConfigError("parameter '" + nh.resolveName(name) + "' has the wrong type");
  return value;
}

/// Reads an optional parameter; keeps `value` (the documented default) when it is unset, throws
/// ConfigError when it is set with the wrong type.
template <typename T>
void optional(const ros::NodeHandle& nh, const std::string& name, T& value) {
  if (!nh.hasParam(name)) return;
  if (!nh.getParam(name, value))
    throw ConfigError("parameter '" + nh.resolveName(name) + "' has the wrong type");
}

}  // namespace ros_params
}  // namespace scanstop
