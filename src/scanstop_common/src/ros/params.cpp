#include "scanstop_common/ros/params.h"

#include <algorithm>
#include <stdexcept>

#include "scanstop_common/config.h"

namespace scanstop {
namespace ros_params {

namespace {
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}
}  // namespace

std::string closestName(const std::string& name, const std::vector<std::string>& known) {
  std::string best;
  size_t best_distance = std::max<size_t>(2, name.size() / 3) + 1;  // more differs: no hint
  size_t best_prefix = 0;  // ties: the longer common prefix ("k_r": "k_r_m", not "k0")
  for (const std::string& k : known) {
    const size_t d = editDistance(name, k);
    size_t prefix = 0;
    while (prefix < name.size() && prefix < k.size() && name[prefix] == k[prefix]) ++prefix;
    if (d < best_distance || (d == best_distance && !best.empty() && prefix > best_prefix))
      best = k, best_distance = d, best_prefix = prefix;
  }
  return best;
}

void ParamReader::optional(const std::string& name, double& value, double lo, double hi, const std::string& unit) {
  optional<double>(name, value);
  requireInRange(resolve(name), value, lo, hi, unit);
}

void ParamReader::optional(const std::string& name, int& value, int lo, int hi) {
  optional<int>(name, value);
  requireInRange(resolve(name), value, lo, hi);
}

void ParamReader::degrees(const std::string& name, double& radians, double lo_deg, double hi_deg) {
  if (name.find("_deg") == std::string::npos)
    throw std::logic_error("ParamReader::degrees: parameter '" + name + "' does not say it is in degrees (_deg)");
  std::string unit = name.substr(name.find("_deg") + 1);  // "deg", "deg_per_m" -> "deg/m"
  if (unit.compare(0, 8, "deg_per_") == 0) unit = "deg/" + unit.substr(8);
  double deg = radians * 180.0 / M_PI;
  optional<double>(name, deg);
  requireInRange(resolve(name), deg, lo_deg, hi_deg, unit);
  radians = deg * M_PI / 180.0;
}

void ParamReader::rejectUnknown() const {
  const std::vector<std::string> unknown_names = unknown();
  if (unknown_names.empty()) return;
  std::vector<std::string> known_sorted = known_;
  std::sort(known_sorted.begin(), known_sorted.end());
  known_sorted.erase(std::unique(known_sorted.begin(), known_sorted.end()), known_sorted.end());
  const std::string prefix = nh_.getNamespace() == "/" ? "/" : nh_.getNamespace() + "/";
  std::string text = unknown_names.size() == 1 ? "unknown parameter " : "unknown parameters ";
  for (size_t i = 0; i < unknown_names.size(); ++i) {
    const std::string& full = unknown_names[i];
    text += (i ? ", '" : "'") + full + "'";
    const std::string close = closestName(full.substr(prefix.size()), known_sorted);
    if (!close.empty()) text += " (did you mean '" + close + "'?)";
  }
  text += ": nothing reads " + std::string(unknown_names.size() == 1 ? "it" : "them") + "; " + node_ + " reads ";
  for (size_t i = 0; i < known_sorted.size(); ++i) text += (i ? ", " : "") + known_sorted[i];
  throw ConfigError(text);
}

}  // namespace ros_params
}  // namespace scanstop
