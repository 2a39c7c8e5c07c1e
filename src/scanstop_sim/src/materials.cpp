#include "scanstop_sim/materials.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <set>

#include "scanstop_common/file_util.h"

namespace scanstop {
namespace sim {
namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string vec(const Eigen::Vector3d& v) { return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]"; }

std::string lineOf(const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  return m.line >= 0 ? " (line " + std::to_string(m.line + 1) + ")" : "";
}

/// Reads one finite number; `what` names it for the error.
double number(const YAML::Node& n, const std::string& source, const std::string& what) {
  double v = 0.0;
  try {
    if (!n.IsScalar()) throw YAML::Exception(n.Mark(), "not a number");
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw MaterialsError(source, what + lineOf(n) + " is not a number");
  }
  if (!std::isfinite(v)) throw MaterialsError(source, what + " = " + num(v) + lineOf(n) + " is not finite");
  return v;
}

Eigen::Vector3d corner(const YAML::Node& n, const std::string& source, const std::string& what) {
  if (!n) throw MaterialsError(source, what + " is missing (three numbers [x, y, z] in metres)");
  if (!n.IsSequence() || n.size() != 3)
    throw MaterialsError(source, what + lineOf(n) + " must be a list of three numbers [x, y, z] in metres");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v[k] = number(n[k], source, what + "[" + std::to_string(k) + "]");
  return v;
}

}  // namespace

const char* materialName(Material m) {
  switch (m) {
    case Material::Diffuse:
      return "diffuse";
    case Material::Retroreflective:
      return "retroreflective";
    case Material::Absorbing:
      return "absorbing";
    case Material::Glass:
      return "glass";
  }
  return "?";
}

MaterialMap parseMaterials(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw MaterialsError(source, std::string("not valid YAML: ") + e.what());
  }
  MaterialMap map;
  map.source = source;
  if (!root.IsMap() || !root["regions"])
    throw MaterialsError(source, "no 'regions' list (expected 'regions:' followed by entries with material, min, max)");
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key != "regions")
      throw MaterialsError(source, "unknown key '" + key + "'" + lineOf(kv.first) + " (only 'regions')");
  }
  const YAML::Node regions = root["regions"];
  if (regions.IsNull()) return map;  // `regions:` with nothing: every surface diffuse
  if (!regions.IsSequence()) throw MaterialsError(source, "'regions'" + lineOf(regions) + " is not a list");
  static const std::set<std::string> kKeys = {"name", "material", "min", "max", "bias_m", "reflect_probability"};
  for (size_t k = 0; k < regions.size(); ++k) {
    const YAML::Node e = regions[k];
    MaterialRegion r;
    r.name = "entry " + std::to_string(k + 1);
    std::string where = "regions entry " + std::to_string(k + 1);
    if (!e.IsMap()) throw MaterialsError(source, where + lineOf(e) + " is not a map (material, min, max)");
    if (const YAML::Node n = e["name"]) {
      if (!n.IsScalar()) throw MaterialsError(source, where + ": 'name'" + lineOf(n) + " is not a string");
      r.name = n.as<std::string>();
      where += " ('" + r.name + "')";
    }
    for (const auto& kv : e) {
      const std::string key = kv.first.as<std::string>();
      if (!kKeys.count(key))
        throw MaterialsError(source, where + ": unknown key '" + key + "'" + lineOf(kv.first) +
                                         " (known: name, material, min, max, bias_m, reflect_probability)");
    }
    const YAML::Node m = e["material"];
    if (!m)
      throw MaterialsError(source, where + ": 'material' is missing (diffuse, retroreflective, absorbing, glass)");
    const std::string mat = m.IsScalar() ? m.as<std::string>() : std::string("<not a string>");
    if (mat == "diffuse")
      r.material = Material::Diffuse;
    else if (mat == "retroreflective")
      r.material = Material::Retroreflective;
    else if (mat == "absorbing")
      r.material = Material::Absorbing;
    else if (mat == "glass")
      r.material = Material::Glass;
    else
      throw MaterialsError(source, where + ": unknown material '" + mat + "'" + lineOf(m) +
                                       " (one of diffuse, retroreflective, absorbing, glass)");
    r.min = corner(e["min"], source, where + ": 'min'");
    r.max = corner(e["max"], source, where + ": 'max'");
    for (int a = 0; a < 3; ++a)
      if (r.min[a] > r.max[a])
        throw MaterialsError(
            source, where + ": min " + vec(r.min) + " > max " + vec(r.max) + " in " + std::string(1, "xyz"[a]));
    if (const YAML::Node n = e["bias_m"]) {
      if (r.material != Material::Retroreflective)
        throw MaterialsError(source, where + ": 'bias_m'" + lineOf(n) +
                                         " is for retroreflective regions only, this one is " +
                                         materialName(r.material));
      r.bias_m = number(n, source, where + ": 'bias_m'");
      if (r.bias_m < 0.0 || r.bias_m > 1.0)
        throw MaterialsError(source, where + ": 'bias_m' = " + num(r.bias_m) + " m is out of range [0, 1] m");
    }
    if (const YAML::Node n = e["reflect_probability"]) {
      if (r.material != Material::Glass)
        throw MaterialsError(source, where + ": 'reflect_probability'" + lineOf(n) +
                                         " is for glass regions only, this one is " + materialName(r.material));
      r.reflect_probability = number(n, source, where + ": 'reflect_probability'");
      if (r.reflect_probability < 0.0 || r.reflect_probability > 1.0)
        throw MaterialsError(
            source, where + ": 'reflect_probability' = " + num(r.reflect_probability) + " is out of range [0, 1]");
    }
    map.regions.push_back(r);
  }
  return map;
}

MaterialMap loadMaterials(const std::string& path) {
  std::string text;
  try {
    text = readFile(path);
  } catch (const IoError& e) {
    throw MaterialsError(path, "cannot read the materials file: " + e.problem());
  }
  return parseMaterials(text, path);
}

std::string materialsPathFor(const std::string& stl_path) {
  const size_t slash = stl_path.find_last_of('/');
  const size_t dot = stl_path.rfind('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
  return (has_ext ? stl_path.substr(0, dot) : stl_path) + ".materials.yaml";
}

}  // namespace sim
}  // namespace scanstop
