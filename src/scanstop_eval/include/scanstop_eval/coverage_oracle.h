#pragma once
/// A known-map reference for exploration (issue #19): how few perfect scans, placed anywhere on the
/// truly reachable floor, see (nearly) all of it, and all of the surface that can be seen from it?
/// Candidate poses on a lattice over the reachable floor, one simulated scan at each (the project's
/// own Simulator, so the scanner's geometry is sim_node's), which floor cells and surface elements
/// each scan sees, and a greedy set cover with an exact check of pairs. ROS-free.
///
/// Frames and units: the world frame of the STL; metres, radians.

#include <Eigen/Core>
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "scanstop_common/pose.h"
#include "scanstop_eval/set_cover.h"
#include "scanstop_eval/surface_elements.h"
#include "scanstop_sim/simulator.h"

namespace scanstop {
namespace eval {

/// The oracle's settings. Body-derived defaults (a test keeps them equal to the sources):
/// robot_radius_m = robot_body/radius (config/robot_body.yaml, 0.26) + the explorer's
/// inflation_margin_m (0.04); z_hi_m = robot_body/height (0.60) + obstacle_height_margin_m (0.03).
struct OracleConfig {
  double grid_m = 0.5;                ///< candidate spacing, a lattice through the start [m], [0.05, 10]
  int planes = 400;                   ///< planes of each candidate's scan, [1, 2000]
  double robot_radius_m = 0.30;       ///< disc of the reachable floor and of the candidates' centres [m], (0, 5]
  double raster_m = 0.05;             ///< raster of the true reachable floor (floor_coverage's) [m], [0.01, 1]
  double cell_m = 0.1;                ///< floor cell, a whole multiple of raster_m [m], [raster_m, 1]
  double floor_tolerance_m = 0.1;     ///< a floor cell is seen when a floor hit (z < z_lo_m) lies this close to
                                      ///< the cell (its square) [m], [0, 1]
  double known_free_m = 0.8;          ///< floor cells whose centre lies this close to a scan's pose count as seen:
                                      ///< the explorer's known_free_radius_m (the cone below the scanner it cannot
                                      ///< see, 0.78 m at 0.45 m height) [m], [0, 5]; 0: floor hits only
  double surface_cell_m = 0.05;       ///< surface element size [m], [0.01, 1]
  double surface_tolerance_m = 0.03;  ///< an element is seen when a hit lies this close to it [m], [0, surface_cell_m]
  double z_lo_m = 0.03;               ///< floor below, obstacle layer and surface above [m]
  double z_hi_m = 0.63;               ///< top of the obstacle layer [m]
  std::vector<double> shares = {0.90, 0.95, 0.99};  ///< coverage targets reported
  double max_pair_work = 5e8;                       ///< bound of the exact pair check (word operations); 0: greedy only
  /// Throws ConfigError naming the field, its value and the range.
  void validate() const;
  /// Raster cells along a floor cell's side.
  int cellsPerFloorCell() const;
};

/// One greedy cover with its targets.
struct CoverResult {
  size_t total = 0;                  ///< elements the shares refer to
  GreedyCover greedy;                ///< the picks (indices into OracleResult::candidates) and the curve
  std::optional<size_t> best_pair;   ///< most elements two scans see, when the pair check ran
  std::vector<CoverTarget> targets;  ///< per OracleConfig::shares

  /// Share of total covered after k greedy picks (k >= 1; the last value beyond the curve's end).
  double shareAfter(size_t k) const;
};

struct OracleResult {
  Pose2D start;                             ///< world frame
  std::vector<Eigen::Vector2d> candidates;  ///< scanned positions (world frame) [m]
  size_t candidates_refused = 0;            ///< lattice points the simulator refused (its disc touched an obstacle)
  size_t floor_cells = 0;                   ///< floor cells (cell_m) holding reachable floor
  double reachable_m2 = 0.0;                ///< the true reachable floor (raster_m) [m^2]
  size_t floor_seen = 0;                    ///< of them, seen by some candidate
  size_t surface_elements = 0;              ///< elements of the world's surface (not floor)
  size_t surface_visible = 0;               ///< of them, seen by some candidate: the visible surface
  CoverResult floor;                        ///< cover of the reachable floor cells (total = floor_cells)
  CoverResult surface;                      ///< cover of the visible surface (total = surface_visible)
  double setup_s = 0.0, scan_s = 0.0, cover_s = 0.0;  ///< wall time of the stages [s]
};

/// Runs the oracle in sim's world from `start` (world frame; the reachable floor is the component of
/// its cell). sim is moved to every candidate (Simulator::reset) and scans there; its error profile
/// is used as it is (perfect for the reference). `progress(done, total)` after each candidate.
/// Throws std::invalid_argument for a start where the disc does not fit, ConfigError for bad
/// settings, std::length_error for a world too large for the grids.
OracleResult runCoverageOracle(sim::Simulator& sim, const Pose2D& start, const OracleConfig& config,
                               const std::function<void(size_t, size_t)>& progress = {});

/// The world's surface elements and which of them are visible from the truly reachable floor: seen
/// by the scan of some candidate of the oracle's lattice (the denominator of a map's surface coverage).
struct VisibleSurface {
  SurfaceElements elements;       ///< every element of the world's surface (not floor)
  std::vector<uint8_t> visible;   ///< per element: 1 when some candidate's scan saw it
  size_t visible_count = 0;       ///< elements with visible = 1
  size_t candidates = 0;          ///< candidates scanned
  size_t candidates_refused = 0;  ///< lattice points the simulator refused
  double seconds = 0.0;           ///< wall time [s]
};

/// The oracle's candidates and their scans, without the set cover: the visible surface (the same
/// definition as OracleResult::surface_visible, for the same settings). Throws as runCoverageOracle.
VisibleSurface visibleSurface(sim::Simulator& sim, const Pose2D& start, const OracleConfig& config,
                              const std::function<void(size_t, size_t)>& progress = {});

}  // namespace eval
}  // namespace scanstop
