#include "scanstop_common/config.h"

#include <cmath>
#include <sstream>

#include "scanstop_common/error.h"

namespace scanstop {
namespace {

std::string withUnit(double v, const std::string& unit) {
  std::ostringstream out;
  out << v;
  if (!unit.empty()) out << ' ' << unit;
  return out.str();
}

}  // namespace

void requireInRange(const std::string& name, double value, double lo, double hi, const std::string& unit) {
  if (!std::isfinite(value) || value < lo || value > hi)
    throw ConfigError("parameter '" + name + "' = " + withUnit(value, unit) + " is out of range [" + withUnit(lo, "") +
                      ", " + withUnit(hi, unit) + "]");
}

void requirePositive(const std::string& name, double value, const std::string& unit) {
  if (!std::isfinite(value) || value <= 0.0)
    throw ConfigError("parameter '" + name + "' = " + withUnit(value, unit) + " must be a finite value > 0");
}

void requireNonNegative(const std::string& name, double value, const std::string& unit) {
  if (!std::isfinite(value) || value < 0.0)
    throw ConfigError("parameter '" + name + "' = " + withUnit(value, unit) + " must be a finite value >= 0");
}

void requireOneOf(const std::string& name, long value, const std::vector<long>& allowed) {
  std::ostringstream list;
  for (size_t i = 0; i < allowed.size(); ++i) {
    if (allowed[i] == value) return;
    list << (i ? ", " : "") << allowed[i];
  }
  throw ConfigError("parameter '" + name + "' = " + std::to_string(value) + " must be one of " + list.str());
}

void requireOneOf(const std::string& name, const std::string& value, const std::vector<std::string>& allowed) {
  std::string list;
  for (size_t i = 0; i < allowed.size(); ++i) {
    if (allowed[i] == value) return;
    list += (i ? ", " : "") + allowed[i];
  }
  throw ConfigError("parameter '" + name + "' = '" + value + "' must be one of " + list);
}

}  // namespace scanstop
