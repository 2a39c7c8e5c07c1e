#include "scanstop_explorer/parameters.h"

#include <yaml-cpp/yaml.h>

#include <iomanip>
#include <set>
#include <sstream>
#include <type_traits>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace explorer {

void BodyMargins::validate() const {
  requireInRange("inflation_margin_m", inflation_margin_m, 0.0, 1.0, "m");
  requireInRange("obstacle_height_margin_m", obstacle_height_margin_m, 0.0, 1.0, "m");
}

void applyBody(const RobotBody& body, const BodyMargins& margins, ExplorerConfig& c) {
  c.planner.robot_radius_m = body.radius_m + margins.inflation_margin_m;
  c.floor.robot_height_m = body.height_m + margins.obstacle_height_margin_m - 0.5 * c.floor.floor_layer_m;
}

namespace {

template <class T>
void readValue(const YAML::Node& node, const std::string& where, T& value) {
  try {
    if (!node.IsScalar()) throw YAML::Exception(node.Mark(), "not a single value");
    if constexpr (std::is_same_v<T, bool>) {
      value = node.as<bool>();
    } else if constexpr (std::is_integral_v<T>) {
      const double d = node.as<double>();
      if (d != static_cast<double>(static_cast<long long>(d)) || d < -2e9 || d > 2e9)
        throw YAML::Exception(node.Mark(), "not an integer");
      value = static_cast<T>(d);
    } else {
      value = node.as<T>();
    }
  } catch (const YAML::Exception&) {
    throw ConfigError(where + " = '" + (node.IsScalar() ? node.Scalar() : std::string("(not a value)")) + "' is not " +
                      (std::is_same_v<T, bool> ? "true or false"
                       : std::is_integral_v<T> ? "an integer"
                                               : "a number"));
  }
}

}  // namespace

void readParameterFile(const std::string& path, ExplorerConfig& c) {
  // missing, a directory, unreadable: said as such (YAML::BadFile only says "bad file")
  const std::string problem = inputFileProblem(path);
  if (!problem.empty()) throw IoError(path, problem + " (the parameter file)");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw IoError(path, "cannot read the parameter file");
  } catch (const YAML::Exception& e) {
    throw IoError(path, std::string("not a YAML file: ") + e.what());
  }
  if (root.IsNull()) return;  // an empty file: the defaults
  if (!root.IsMap()) throw ConfigError(path + ": expected a map of parameter: value");
  std::set<std::string> done;
  const auto where = [&](const std::string& name) { return path + ": " + name; };
  forEachParameter(c, [&](const char* name, auto& value) {
    if (const YAML::Node n = root[name]) readValue(n, where(name), value);
    done.insert(name);
  });
  BodyMargins margins;
  if (const YAML::Node n = root["inflation_margin_m"])
    readValue(n, where("inflation_margin_m"), margins.inflation_margin_m);
  if (const YAML::Node n = root["obstacle_height_margin_m"])
    readValue(n, where("obstacle_height_margin_m"), margins.obstacle_height_margin_m);
  try {
    margins.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
  applyBody(RobotBody(), margins, c);
  if (const YAML::Node n = root["robot_radius_m"]) readValue(n, where("robot_radius_m"), c.planner.robot_radius_m);
  if (const YAML::Node n = root["robot_height_m"]) readValue(n, where("robot_height_m"), c.floor.robot_height_m);
  done.insert({"inflation_margin_m", "obstacle_height_margin_m", "robot_radius_m", "robot_height_m"});
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (!done.count(key))
      throw ConfigError(path + ": unknown explorer parameter '" + key +
                        "' (a typo? the names carry their unit, e.g. k_r_m)");
  }
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(path + ": " + e.what());
  }
}

namespace {
std::string yamlValue(bool v) { return v ? "true" : "false"; }
std::string yamlValue(int v) { return std::to_string(v); }
std::string yamlValue(double v) {
  std::ostringstream out;
  out << std::setprecision(17) << v;
  return out.str();
}
std::string yamlValue(const std::string& v) { return "\"" + v + "\""; }
}  // namespace

std::string parameterFileText(const ExplorerConfig& c, const std::string& comment) {
  std::ostringstream out;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  ExplorerConfig copy = c;
  forEachParameter(copy, [&](const char* name, auto& value) { out << name << ": " << yamlValue(value) << "\n"; });
  out << "robot_radius_m: " << yamlValue(c.planner.robot_radius_m) << "\n";
  out << "robot_height_m: " << yamlValue(c.floor.robot_height_m) << "\n";
  return out.str();
}

}  // namespace explorer
}  // namespace scanstop
