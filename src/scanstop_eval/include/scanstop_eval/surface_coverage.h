#pragma once
/// Surface completeness of a map (issue #19 point 5): the share of the world's surface that is
/// visible from the truly reachable floor (VisibleSurface, the coverage oracle's definition) and that
/// the map holds: an element counts as held when a map point lies within a tolerance (3 cm) of it.
/// Ground-truth evaluation for simulated runs; ROS-free.
///
/// Frames and units: the world frame of the STL; metres.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_eval/coverage_oracle.h"

namespace scanstop {
namespace eval {

/// Counts the visible surface elements that map points (world frame) come close to.
class SurfaceCoverage {
 public:
  /// tolerance_m in [0, the elements' cell] [m]; throws ConfigError otherwise.
  SurfaceCoverage(const VisibleSurface& visible, double tolerance_m);

  /// Adds map points in the world frame [m]; non-finite points are skipped.
  void add(const std::vector<Eigen::Vector3f>& points_world);

  size_t visible() const { return visible_.visible_count; }
  size_t covered() const { return covered_; }  ///< visible elements held by the map
  size_t points() const { return points_; }    ///< finite points added
  /// covered / visible [0..1]; 0 when nothing is visible.
  double share() const;

 private:
  const VisibleSurface& visible_;
  float tolerance_;
  std::vector<uint8_t> held_;
  size_t covered_ = 0;
  size_t points_ = 0;
};

/// The surface coverage of a map directory: every loadable scan at its map pose (as finally
/// optimized, poses.csv), taken into the world frame by world_T_map (the map frame's pose in the
/// world: the simulated start). Scans that fail to load are skipped and named in `problems`.
struct MapSurfaceCoverage {
  size_t scans = 0;    ///< scans added
  size_t points = 0;   ///< their finite points
  size_t visible = 0;  ///< visible surface elements
  size_t covered = 0;  ///< of them, held by the map
  double share = 0.0;  ///< covered / visible [0..1]
};
MapSurfaceCoverage mapSurfaceCoverage(const VisibleSurface& visible, const MapDirectory& map, const Pose2D& world_T_map,
                                      double tolerance_m, std::vector<std::string>* problems = nullptr);

/// A simulated run's surface coverage in one call (mission_node's report): the surface visible from
/// the truly reachable floor (a perfect simulator of `world`, the oracle's candidate scans with
/// `planes` planes for a robot of robot_radius_m), then mapSurfaceCoverage at the oracle's 3 cm.
/// start: the map frame in the world. Throws as visibleSurface and mapSurfaceCoverage.
struct RunSurfaceCoverage {
  MapSurfaceCoverage held;
  size_t candidates = 0;   ///< candidate scans of the visible surface
  double seconds = 0.0;    ///< wall time of the visible surface [s]
  VisibleSurface visible;  ///< the visible surface itself (for the mesh's coverage, measureSurfaceAccuracy)
};
RunSurfaceCoverage surfaceCoverageOfRun(const TriangleMesh& world, const std::string& world_name, const Pose2D& start,
                                        const MapDirectory& map, double robot_radius_m, int planes);

}  // namespace eval
}  // namespace scanstop
