#pragma once
/// Parameter reading for nodes: a missing required parameter or a value of the wrong type is an
/// error naming the parameter (with its full namespace), never a silent default.

#include <ros/node_handle.h>
#include <ros/param.h>

#include <string>
#include <utility>
#include <vector>

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

/// Parameters set in nh's namespace (directly or below it) whose first name component is not in
/// `known`: typos such as `k_r` for `k_r_m` that would otherwise be ignored silently. Full names.
inline std::vector<std::string> unknownParameters(const ros::NodeHandle& nh, const std::vector<std::string>& known) {
  std::vector<std::string> names, unknown;
  ros::param::getParamNames(names);
  const std::string prefix = nh.getNamespace() == "/" ? "/" : nh.getNamespace() + "/";
  for (const std::string& name : names) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key = name.substr(prefix.size());
    bool is_known = false;
    for (const std::string& k : known)
      is_known = is_known || key == k || key.compare(0, k.size() + 1, k + "/") == 0;
    if (!is_known) unknown.push_back(name);
  }
  return unknown;
}

/// Checks frame-id parameters (name, value): each non-empty, without a leading '/' or space, and all
/// different. Throws ConfigError naming the parameter(s) with their full names.
inline void requireFrames(const ros::NodeHandle& nh, const std::vector<std::pair<std::string, std::string>>& frames) {
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i].second.empty() || frames[i].second.find_first_of(" /") == 0)
      throw ConfigError("parameter '" + nh.resolveName(frames[i].first) + "' = '" + frames[i].second +
                        "' must be a non-empty frame id without a leading '/' or space");
    for (size_t j = 0; j < i; ++j)
      if (frames[i].second == frames[j].second)
        throw ConfigError("parameters '" + nh.resolveName(frames[j].first) + "' and '" + nh.resolveName(frames[i].first) +
                          "' are both '" + frames[i].second + "': the frames must differ");
  }
}

}  // namespace ros_params
}  // namespace scanstop
