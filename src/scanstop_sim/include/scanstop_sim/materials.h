#pragma once
/// Per-surface materials of a simulated world (issue #20, thesis chapter 8 and 3.2): the URG-04LX
/// reads highly reflective surfaces short (the table leg's reflector of fig. 8.7: about 10 cm),
/// gets no return from strongly absorbing ones (the LCD monitor of fig. 8.8) and sees through
/// glass.
///
/// A world's materials are a small YAML file next to its STL, `<world>.materials.yaml` (or the
/// file sim_node's parameter `materials_file` names): a list of axis-aligned boxes in the world
/// frame, each with a material; a triangle belongs to the first box that contains its centroid,
/// triangles in no box are `diffuse`.
///
///   regions:
///     - name: table_leg            # optional, used in messages
///       material: retroreflective  # diffuse | retroreflective | absorbing | glass
///       min: [5.2, 4.6, 0.0]       # [m] box corners, world frame
///       max: [5.3, 4.7, 0.7]
///       bias_m: 0.10               # retroreflective only: reads short by this much [m], default 0.10
///     - material: glass
///       min: [0, 3, 0]
///       max: [0.1, 5, 2]
///       reflect_probability: 0.05  # glass only: share of beams the pane itself returns, default 0

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "scanstop_common/error.h"

namespace scanstop {
namespace sim {

enum class Material : uint8_t {
  Diffuse,          ///< a normal reading of the surface
  Retroreflective,  ///< reads short by bias_m
  Absorbing,        ///< no return (NaN, unless the sensor model draws a random reading)
  Glass,            ///< the beam passes through (returns the pane with reflect_probability)
};

/// "diffuse", "retroreflective", "absorbing", "glass".
const char* materialName(Material m);

struct MaterialRegion {
  std::string name;  ///< from the file, or "entry <k>"
  Material material = Material::Diffuse;
  Eigen::Vector3d min = Eigen::Vector3d::Zero(), max = Eigen::Vector3d::Zero();  ///< [m], world frame
  double bias_m = 0.10;              ///< retroreflective: the reading is this much short [m]
  double reflect_probability = 0.0;  ///< glass: probability that the pane returns the beam
  bool contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};

struct MaterialMap {
  std::string source;  ///< the file it was read from (for messages)
  std::vector<MaterialRegion> regions;
};

/// A materials file that cannot be read or is wrong; what() names the file, the entry and the problem.
class MaterialsError : public IoError {
 public:
  using IoError::IoError;
};

/// Parses the YAML text of a materials file; `source` names it in errors. Throws MaterialsError
/// naming source, entry (index and name) and problem: not YAML, no `regions` list, an unknown
/// key or material, a corner that is not three finite numbers, min > max, bias_m outside [0, 1] m,
/// reflect_probability outside [0, 1], or a parameter given for a material that has none.
MaterialMap parseMaterials(const std::string& yaml_text, const std::string& source);
/// Reads and parses a materials file; a missing file is a MaterialsError naming it.
MaterialMap loadMaterials(const std::string& path);
/// The materials file that belongs to an STL world: worlds/room.stl -> worlds/room.materials.yaml.
std::string materialsPathFor(const std::string& stl_path);

}  // namespace sim
}  // namespace scanstop
