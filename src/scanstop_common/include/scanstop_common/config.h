#pragma once
/// Validation helpers for configuration structs: each throws ConfigError with a message naming
/// the parameter, its value and what was allowed, so a node can print it and exit.

#include <string>
#include <vector>

namespace scanstop {

/// Requires lo <= value <= hi and a finite value.
void requireInRange(const std::string& name, double value, double lo, double hi, const std::string& unit = "");
/// Requires value > 0 and finite.
void requirePositive(const std::string& name, double value, const std::string& unit = "");
/// Requires value >= 0 and finite.
void requireNonNegative(const std::string& name, double value, const std::string& unit = "");
/// Requires value to be one of the allowed integers.
void requireOneOf(const std::string& name, long value, const std::vector<long>& allowed);
/// Requires value to be one of the allowed strings.
void requireOneOf(const std::string& name, const std::string& value, const std::vector<std::string>& allowed);

}  // namespace scanstop
