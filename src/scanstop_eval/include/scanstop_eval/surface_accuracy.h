#pragma once
/// Accuracy of a map or a mesh against the world it was made in (issue #20 point 4): the distance of
/// its points (a mesh: its vertices and area-weighted samples on its faces) to the world's true
/// surfaces, exact point-to-triangle distances through a uniform grid over the world's triangles,
/// and the share of the visible surface (VisibleSurface, the coverage oracle's) it covers within a
/// tolerance. Ground-truth evaluation for simulated runs; ROS-free.
///
/// Frames and units: the world frame of the STL; inputs in the map frame are taken into it by
/// world_T_map (the simulated start pose, as mapSurfaceCoverage does); metres.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"
#include "scanstop_eval/coverage_oracle.h"

namespace scanstop {
namespace eval {

/// Squared distance from p to the triangle (a, b, c) (a degenerate one: to its segments) [m^2].
float pointTriangleDistance2(const Eigen::Vector3f& p, const Eigen::Vector3f& a, const Eigen::Vector3f& b,
                             const Eigen::Vector3f& c);

/// Exact distance to the nearest triangle of a mesh (the world), through a uniform grid of cubes that
/// lists the triangles passing near each cube. Thread-safe queries.
class WorldSurfaceDistance {
 public:
  /// cell_m: the grid's cube [m]; <= 0 chooses one (0.1 m, coarser when the bounding box would need
  /// more than max_cells cubes). Throws std::invalid_argument for a mesh without triangles.
  explicit WorldSurfaceDistance(const TriangleMesh& world, double cell_m = 0.0, double max_cells = 4e6);

  /// Distance from p to the nearest triangle [m] (+inf for a non-finite p).
  float distance(const Eigen::Vector3f& p) const;

  size_t triangles() const { return a_.size(); }
  double cell() const { return cell_; }

 private:
  float bruteForce2(const Eigen::Vector3f& p) const;
  float tri2(const Eigen::Vector3f& p, uint32_t t) const { return pointTriangleDistance2(p, a_[t], b_[t], c_[t]); }

  std::vector<Eigen::Vector3f> a_, b_, c_;  ///< corners per triangle
  float cell_ = 0.1f;
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  int dims_[3] = {0, 0, 0};
  std::vector<uint32_t> start_;  ///< CSR: triangles of cube i are ids_[start_[i] .. start_[i + 1])
  std::vector<uint32_t> ids_;
};

/// Area-weighted samples on a mesh's faces: each triangle is split into k^2 congruent sub-triangles
/// (k = ceil(longest edge / spacing_m)), one sample at each one's centroid with weight = its area
/// [m^2]. Degenerate faces give none. Throws std::invalid_argument for spacing_m <= 0 or a face
/// index out of range.
struct SurfaceSamples {
  std::vector<Eigen::Vector3f> points;  ///< [m]
  std::vector<float> weights;           ///< area each sample stands for [m^2]
  double area_m2 = 0.0;                 ///< total area of the faces
};
SurfaceSamples sampleMeshSurface(const TriangleMesh& mesh, double spacing_m);

/// Distribution of distances, optionally weighted (area of mesh samples); quantiles are the smallest
/// distance whose cumulative weight reaches the share.
struct DistanceStats {
  size_t count = 0;  ///< finite distances
  double median_m = 0.0, mean_m = 0.0, rms_m = 0.0, p95_m = 0.0, max_m = 0.0;
  std::vector<double> within_m;  ///< thresholds [m] ...
  std::vector<double> share;     ///< ... and the (weighted) share of distances at or below each [0..1]
};
/// Statistics of (distance [m], weight) pairs (taken by value: sorted in place); non-finite distances
/// and weights <= 0 are left out.
DistanceStats distanceStats(std::vector<std::pair<float, float>> distance_weight,
                            const std::vector<double>& within_m = {0.01, 0.02, 0.03, 0.05});
/// Unweighted (every weight 1).
DistanceStats distanceStats(const std::vector<float>& distances,
                            const std::vector<double>& within_m = {0.01, 0.02, 0.03, 0.05});

/// What is measured: a mesh (.ply with faces, .stl), a point cloud (.ply without faces, .pcd, .xyz,
/// .txt) or a map directory (poses.csv and its scans, every scan at its final map pose).
struct AccuracyInput {
  enum class Kind { Mesh, Cloud, MapDirectory };
  Kind kind = Kind::Cloud;
  std::string path;
  TriangleMesh mesh;                    ///< Kind::Mesh (map frame)
  std::vector<Eigen::Vector3f> points;  ///< Kind::Cloud and Kind::MapDirectory (map frame)
  size_t scans = 0;                     ///< Kind::MapDirectory: scans loaded
  std::vector<std::string> problems;    ///< scans skipped, directory problems
};
/// Reads by kind: a directory is a map directory (it must hold poses.csv), else by extension. Throws
/// IoError naming the path: missing, not a map directory, an unknown extension, unreadable content,
/// nothing (no points, no scans) in it. A map directory is read strictly (openMapForTool): a bad line
/// of poses.csv or a bad scan file is an IoError naming it, unless skip_bad (then it is skipped and
/// listed in problems).
AccuracyInput loadAccuracyInput(const std::string& path, bool skip_bad = false);
const char* kindName(AccuracyInput::Kind kind);

struct AccuracyConfig {
  double sample_spacing_m = 0.01;  ///< spacing of a mesh's face samples [m], > 0
  double tolerance_m = 0.03;       ///< coverage tolerance [m], [0, the visible surface's element]
  std::vector<double> within_m = {0.01, 0.02, 0.03, 0.05};  ///< thresholds of the shares [m]
};

struct SurfaceAccuracy {
  size_t triangles = 0, vertices = 0;         ///< the mesh's (0 for points)
  size_t points = 0;                          ///< the cloud's or the map's finite points (0 for a mesh)
  size_t samples = 0;                         ///< face samples of a mesh
  double area_m2 = 0.0;                       ///< the mesh's area
  DistanceStats vertex_distance;              ///< a mesh: its vertices; points: the points
  DistanceStats surface_distance;             ///< a mesh: area-weighted face samples; points: = vertex_distance
  size_t visible = 0, covered = 0;            ///< visible surface elements, of them within tolerance
  double coverage = 0.0;                      ///< covered / visible [0..1] (0 without a visible surface)
  double distance_s = 0.0, coverage_s = 0.0;  ///< wall time [s]
};

/// Measures the input against the world: its points (a mesh: all its vertices, and its faces'
/// samples) taken into the world by world_T_map; coverage against `visible` when given: its elements
/// within config.tolerance_m of a point or of a face sample (a mesh's vertices alone cover nothing:
/// a vertex no face uses is no surface). Throws ConfigError for bad settings.
SurfaceAccuracy measureSurfaceAccuracy(const WorldSurfaceDistance& world, const VisibleSurface* visible,
                                       const AccuracyInput& input, const Pose2D& world_T_map,
                                       const AccuracyConfig& config = AccuracyConfig());

}  // namespace eval
}  // namespace scanstop
