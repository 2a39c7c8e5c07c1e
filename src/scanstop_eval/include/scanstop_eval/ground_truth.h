#pragma once
/// Ground-truth floor coverage in simulation (evaluation, not exploration: the explorer never sees it): which share of
/// the floor the robot could really reach (from the world mesh) did the explorer's floor map observe? The explorer's
/// own `coverage` only counts cells it can reach in its own map: a door it wrongly thinks closed hides the rooms behind
/// it and still gives 100 %.

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_explorer/explorer.h"
#include "scanstop_explorer/grid.h"

namespace scanstop {
namespace eval {

using explorer::ExplorerConfig;
using explorer::GridGeometry;

/// The floor a robot disc can really reach in a world, from the world's mesh, on a world-frame grid.
struct ReachableFloor {
  GridGeometry geometry;  ///< world frame
  cv::Mat obstacle;       ///< CV_8U 0/1: cells of triangles reaching into the obstacle layer
  cv::Mat blocked;        ///< CV_8U 0/1: obstacle cells and cells off the floor (no floor triangle)
  cv::Mat centres;        ///< CV_8U 0/1: where the disc's centre can stand, 4-connected to the start
  cv::Mat reachable;      ///< CV_8U 0/1: the cells the disc sweeps from those centres
  double reachable_m2 = 0.0;
};

/// Rasterises the world mesh's triangles that reach into the obstacle layer (z in [z_lo, z_hi]) onto a
/// world-frame grid (resolution [m]), and those below z_lo as floor; free cells are floor cells
/// (every cell when the mesh has no floor triangle) without an obstacle. Erodes the free cells by
/// robot_radius_m (the disc stays on the floor: an edge of the floor bounds it like a wall), takes the
/// 4-connected component of the start position (the centres) and grows it back by the radius: the
/// true reachable floor. Throws std::invalid_argument naming a bad input (empty mesh, a grid beyond
/// 2e7 cells, start outside the world, off its floor, inside an obstacle or where the disc does not fit).
ReachableFloor reachableFloor(const TriangleMesh& world, const Pose2D& start_world, double robot_radius_m,
                              double resolution = 0.05, double z_lo = 0.03, double z_hi = 0.63);

struct GroundTruthCoverage {
  double reachable_m2 = 0.0;              ///< true reachable floor (cells the robot disc can sweep from the start)
  double observed_m2 = 0.0;               ///< of it, floor in the explorer's map (within tolerance)
  double coverage = 0.0;                  ///< observed / reachable
  size_t scans = 0;                       ///< scans of the map (groundTruthCoverageOfMap; 0 otherwise)
  double robot_radius_m = 0.0;            ///< the robot disc the reachable floor was swept with [m]
  GridGeometry geometry;                  ///< world frame grid of the masks
  cv::Mat obstacle, reachable, observed;  ///< CV_8U 0/1
};

/// The true reachable floor (reachableFloor()) against the explorer's floor grid: `states`
/// (CellState, map frame, `map_geometry`) are the explorer's floor grid; T_world_map maps it into the
/// world. A reachable cell is observed when a floor cell of the map
/// lies within tolerance_m of it (SLAM drift). Throws std::invalid_argument naming a bad input
/// (empty mesh, start inside an obstacle, bad sizes).
GroundTruthCoverage groundTruthCoverage(const TriangleMesh& world, const Pose2D& start_world, const cv::Mat& states,
                                        const GridGeometry& map_geometry, const Pose2D& T_world_map,
                                        double robot_radius_m, double resolution = 0.05, double z_lo = 0.03,
                                        double z_hi = 0.63, double tolerance_m = 0.1);

/// The same for a map directory: builds the explorer's floor map (with `config`, the explorer's
/// configuration of the run) from its scans, whose map frame is start_world in the world (as
/// sim_node's), and compares. `problems` receives the map directory's skipped files. Throws
/// std::invalid_argument for an empty map.
GroundTruthCoverage groundTruthCoverageOfMap(const TriangleMesh& world, const Pose2D& start_world,
                                             const MapDirectory& map, double robot_radius_m, double tolerance_m = 0.1,
                                             std::vector<std::string>* problems = nullptr,
                                             const ExplorerConfig& config = ExplorerConfig());

/// The same for a run: the explorer configuration is the run's own file (explorer_node writes it as
/// <explorer run_dir>/config.yaml; explorer::readParameterFile reads it), the robot radius that
/// file's robot_radius_m unless `robot_radius_m` is given. A missing file: the explorer's defaults,
/// said in *note (left empty otherwise). Throws as groundTruthCoverageOfMap, and IoError / ConfigError
/// naming a file that exists but cannot be used.
GroundTruthCoverage groundTruthCoverageOfRun(const TriangleMesh& world, const Pose2D& start_world,
                                             const MapDirectory& map, const std::string& explorer_config_file,
                                             std::optional<double> robot_radius_m, std::string* note = nullptr);

}  // namespace eval
}  // namespace scanstop
