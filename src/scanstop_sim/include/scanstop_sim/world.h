#pragma once
/// A static STL world for the simulator: an Embree BVH for ray casting and a 2D obstacle map (the
/// world's geometry in the robot's height band) for collision checks of the robot disc.
///
/// Units: metres; z up; the floor lies in the z = 0 plane (thesis 6.1).

#include <embree3/rtcore.h>

#include <Eigen/Core>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_sim/materials.h"

namespace scanstop {
namespace sim {

/// How a world is checked and which geometry blocks the robot.
struct WorldOptions {
  bool require_floor = true;        ///< a world without floor triangles near z = 0 is an error
  double floor_tolerance_m = 0.01;  ///< |z| below which a horizontal triangle counts as floor
  double obstacle_min_z_m = 0.03;   ///< geometry above this height blocks the robot (thresholds, carpets below) [m]
  double obstacle_max_z_m = 0.60;   ///< ... and below this height (the robot's height) [m]
  /// The world's surface materials (materials.h). Empty: World::load takes `<world>.materials.yaml`
  /// next to the STL when that file exists (every surface diffuse otherwise); fromMesh none. A
  /// path: that file, which must exist.
  std::string materials_file;
};

/// The first surface along a ray.
struct RayHit {
  static constexpr unsigned kNone = 0xFFFFFFFFu;
  float t = std::numeric_limits<float>::infinity();  ///< distance along the unit direction [m]
  unsigned prim = kNone;                             ///< the triangle's index in mesh().faces
  bool hit() const { return prim != kNone; }
};

/// A convex 2D polygon of the obstacle map (a triangle's part in the robot's height band, seen
/// from above; degenerate for walls) [m].
using Polygon2D = std::vector<Eigen::Vector2d>;

class World {
 public:
  /// Loads and validates an STL world; throws IoError naming the file and the problem (missing,
  /// malformed, empty, no floor).
  static World load(const std::string& path, const WorldOptions& options = WorldOptions());
  /// Builds a world from a mesh in memory (`name` for messages); same checks as load().
  static World fromMesh(const TriangleMesh& mesh, const std::string& name,
                        const WorldOptions& options = WorldOptions());

  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  ~World();

  /// Distance [m] along the unit direction to the first surface, or +inf when nothing is hit
  /// within max_range.
  double castRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float max_range) const;
  /// The first surface hit at a distance in [tnear, tfar] along the unit direction, with the
  /// triangle it belongs to (Embree's primID); castRay(o, d, r) == intersect(o, d, 0, r).t.
  RayHit intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear, float tfar) const;
  /// Casts many rays (parallel); ranges[i] = +inf for a miss.
  void castRays(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& directions,
                float max_range, std::vector<float>& ranges) const;

  /// True when a disc of `radius` centred at p touches an obstacle of the 2D obstacle map.
  bool discCollides(const Eigen::Vector2d& p, double radius) const;
  /// Smallest distance from p to an obstacle [m] (0 inside one, +inf when there are none).
  double clearance(const Eigen::Vector2d& p) const;
  /// clearance(p), searched only out to max_m (the obstacle grid's cells near p): max_m when no
  /// obstacle is closer [m].
  double clearanceWithin(const Eigen::Vector2d& p, double max_m) const;

  /// Assigns every triangle the material of the first region containing its centroid (diffuse
  /// when none does); replaces earlier materials.
  void setMaterials(const MaterialMap& materials);
  const MaterialMap& materials() const { return materials_; }
  bool hasMaterials() const { return !face_region_.empty(); }
  /// The region triangle `prim` belongs to, or nullptr (diffuse).
  const MaterialRegion* materialOf(unsigned prim) const {
    if (face_region_.empty() || prim >= face_region_.size()) return nullptr;
    const int r = face_region_[prim];
    return r < 0 ? nullptr : &materials_.regions[static_cast<size_t>(r)];
  }
  /// Number of triangles in each region of materials() (a region with none is likely a typo).
  std::vector<size_t> regionCounts() const;
  /// Unit normal of triangle `prim` (zero for a degenerate one).
  const Eigen::Vector3f& faceNormal(unsigned prim) const { return face_normals_[prim]; }

  const TriangleMesh& mesh() const { return mesh_; }
  const std::string& name() const { return name_; }
  Eigen::Vector3f minCorner() const { return min_; }
  Eigen::Vector3f maxCorner() const { return max_; }
  size_t floorTriangles() const { return floor_triangles_; }
  const std::vector<Polygon2D>& obstacles() const { return polygons_; }
  /// The Embree scene (for the benchmark's bare loop).
  RTCScene scene() const;

 private:
  World();
  void buildObstacleMap(const WorldOptions& options);
  std::vector<int> cellsNear(const Eigen::Vector2d& p, double radius) const;

  struct Embree;
  std::unique_ptr<Embree> embree_;
  TriangleMesh mesh_;
  std::string name_;
  Eigen::Vector3f min_, max_;
  size_t floor_triangles_ = 0;
  std::vector<Eigen::Vector3f> face_normals_;
  MaterialMap materials_;
  std::vector<int> face_region_;  ///< per triangle: index into materials_.regions, -1 diffuse; empty: all diffuse
  double distanceTo(const Polygon2D& poly, const Eigen::Vector2d& p) const;

  // Obstacle map: convex polygons in a uniform grid of cells.
  std::vector<Polygon2D> polygons_;
  double cell_m_ = 0.5;
  Eigen::Vector2d grid_origin_;
  int grid_w_ = 0, grid_h_ = 0;
  std::vector<std::vector<int>> grid_;
};

}  // namespace sim
}  // namespace scanstop
