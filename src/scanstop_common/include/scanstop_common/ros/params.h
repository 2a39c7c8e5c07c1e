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
  if (!nh.getParam(name, value)) throw ConfigError("parameter '" + nh.resolveName(name) + "' has the wrong type");
  return value;
}

/// Reads an optional parameter; keeps `value` (the documented default) when it is unset, throws
/// ConfigError when it is set with the wrong type.
template <typename T>
void optional(const ros::NodeHandle& nh, const std::string& name, T& value) {
  if (!nh.hasParam(name)) return;
  if (!nh.getParam(name, value)) throw ConfigError("parameter '" + nh.resolveName(name) + "' has the wrong type");
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
    for (const std::string& k : known) is_known = is_known || key == k || key.compare(0, k.size() + 1, k + "/") == 0;
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
        throw ConfigError("parameters '" + nh.resolveName(frames[j].first) + "' and '" +
                          nh.resolveName(frames[i].first) + "' are both '" + frames[i].second +
                          "': the frames must differ");
  }
}

/// One reader of a node's private parameters, the same in every node: it reads with the checks of
/// require()/optional(), records every name it was asked for, converts a parameter in degrees
/// (its name says so: `_deg`) to radians, checks frame ids, and at the end refuses any parameter set in
/// the node's namespace that nothing read (rejectUnknown(): an error that names it, the closest known
/// name, and every known one). Names are relative to the node handle (usually "~").
class ParamReader {
 public:
  /// `node`: the node's name in messages ("icp_slam_node").
  ParamReader(const ros::NodeHandle& pnh, std::string node) : nh_(pnh), node_(std::move(node)) {}

  template <typename T>
  T require(const std::string& name) {
    known_.push_back(name);
    return ros_params::require<T>(nh_, name);
  }
  /// Keeps `value` (the documented default) when unset; returns whether it was set.
  template <typename T>
  bool optional(const std::string& name, T& value) {
    known_.push_back(name);
    if (!nh_.hasParam(name)) return false;
    ros_params::optional(nh_, name, value);
    return true;
  }
  /// optional() of a number that must lie in [lo, hi] (unit for the message).
  void optional(const std::string& name, double& value, double lo, double hi, const std::string& unit = "");
  void optional(const std::string& name, int& value, int lo, int hi);
  /// A parameter in degrees (the name contains "_deg"): `radians` holds the default in radians and
  /// receives the value in radians; [lo_deg, hi_deg] is checked in degrees.
  void degrees(const std::string& name, double& radians, double lo_deg, double hi_deg);
  /// Whether the parameter is set (the name counts as known).
  bool has(const std::string& name) {
    known_.push_back(name);
    return nh_.hasParam(name);
  }
  /// Names read by other code (main(), another reader on the same namespace): known, not read here.
  /// A name covers the parameters below it ("robot_body" covers "robot_body/radius").
  void known(const std::vector<std::string>& names) { known_.insert(known_.end(), names.begin(), names.end()); }
  /// Frame ids (name, value) already read: each non-empty, no leading '/' or space, all different.
  void frames(const std::vector<std::pair<std::string, std::string>>& frames) const { requireFrames(nh_, frames); }
  /// Parameters set in the namespace that no call above asked for (full names, sorted).
  std::vector<std::string> unknown() const { return unknownParameters(nh_, known_); }
  /// Throws ConfigError "unknown parameter(s) /ns/k_r (did you mean 'k_r_m'?); explorer_node reads a, b, ..."
  void rejectUnknown() const;
  /// The full name of a parameter, for messages.
  std::string resolve(const std::string& name) const { return nh_.resolveName(name); }
  const ros::NodeHandle& handle() const { return nh_; }
  const std::string& node() const { return node_; }
  /// Every name asked for so far, in order.
  const std::vector<std::string>& names() const { return known_; }

 private:
  ros::NodeHandle nh_;
  std::string node_;
  std::vector<std::string> known_;
};

/// The known name closest to `name` by edit distance, or "" when none is close (at most a third of
/// the name's letters differ). For "did you mean" hints.
std::string closestName(const std::string& name, const std::vector<std::string>& known);

}  // namespace ros_params
}  // namespace scanstop
