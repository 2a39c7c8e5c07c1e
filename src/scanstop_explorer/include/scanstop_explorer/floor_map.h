#pragma once
/// Floor extraction (thesis 5.2): registered 3D scans -> a 2D grid of floor / obstacle / unknown
/// cells whose bounds grow with the map.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "scanstop_explorer/grid.h"

namespace scanstop {
namespace explorer {

/// Cell states of the floor grid (CV_8U values).
/// Fills unknown gaps of the floor: unknown cells in the morphological closing of the floor cells
/// with a disc of radius_cells become floor (obstacles never change; a straight floor border
/// does not move).
void fillFloorGaps(cv::Mat& states, double radius_cells);

enum CellState : uint8_t {
  kUnknown = 0,   ///< no floor and no obstacle point
  kFloor = 1,     ///< floor points only (or known free: the robot stood there)
  kObstacle = 2,  ///< some scan put at least min_obstacle_points points into the robot's height layer
                  ///< (or min_obstacle_scans scans put one each)
                  ///< (and the cell is not speckle, see FloorConfig::speckle_min_points)
};

/// Speckle removal on an obstacle mask (CV_8U, non-zero = obstacle): clears every 8-connected
/// component of at most max_cells cells whose cells all have max_points (CV_32S, most points one
/// scan put into the cell) below min_points. Returns the number of cells cleared.
int removeObstacleSpeckle(cv::Mat& obstacle, const cv::Mat& max_points, int min_points, int max_cells);

/// Parameters of the floor extraction.
struct FloorConfig {
  double resolution_m = 0.05;   ///< grid cell edge [m], (0.005, 1]
  double floor_layer_m = 0.06;  ///< d_floor: thickness of the floor layer centred on z = 0 [m], (0, 0.5]
  double robot_height_m = 0.6;  ///< d_robot: thickness of the obstacle layer above the floor layer [m], (0, 5]
  double grid_margin_m = 1.0;   ///< unknown margin kept around the data when the grid grows [m], [0, 20]
  int min_floor_points = 1;     ///< floor points a cell needs to count as floor, [1, 1000]
  int min_obstacle_points = 2;  ///< obstacle-layer points ONE scan must put into a cell to make it an
                                ///< obstacle (real obstacles give many per scan, random outlier
                                ///< ranges rarely two in one cell), [1, 1000]
  int speckle_min_points = 5;   ///< speckle removal: an obstacle component (8-connected) of at most
                                ///< speckle_max_cells cells none of whose cells got this many
                                ///< obstacle-layer points from one scan is a stray reading (noise,
                                ///< a random range) and not an obstacle; a real thin obstacle (table
                                ///< leg) gives many points per scan or spreads over more cells;
                                ///< <= min_obstacle_points: off, [1, 1000]
  int speckle_max_cells = 2;    ///< largest component that can be speckle, [1, 100]
  /// Sparse obstacle evidence (issue #18 point 2): a cell into which this many different scans
  /// each put at least one obstacle-layer point is an obstacle too, even when no single scan put
  /// min_obstacle_points there (an overhanging table edge or sofa arm seen at grazing angles, an
  /// underside facing away). Isolated cells still pass the speckle rule. 0 = off, [0, 1000]
  int min_obstacle_scans = 3;
  double max_extent_m = 500.0;       ///< points farther than this from the origin are ignored [m], (0, 1e4]
  double floor_fill_radius_m = 0.1;  ///< unknown gaps in the floor narrower than twice this become floor
                                     ///< (morphological closing of the floor over unknown cells only;
                                     ///< 0 = off, the thesis' plain extraction) [m], [0, 1]

  /// Throws ConfigError naming the parameter, its value and the allowed range.
  void validate() const;
};

/// The incremental floor grid: add scans (map frame) and known-free discs; read the states.
class FloorMap {
 public:
  explicit FloorMap(const FloorConfig& config = FloorConfig());

  /// Adds the points of one scan in the map frame (z = 0 is the floor) [m]. Non-finite points
  /// and points outside both layers are skipped; the grid grows to hold every used point plus
  /// grid_margin_m. Returns the number of points that marked floor or obstacle.
  size_t addPoints(const std::vector<Eigen::Vector3f>& points_map);
  /// Marks the disc of radius_m around a map point as known free floor (where the robot stood;
  /// the scanner cannot see the floor under the robot): unknown cells of the disc that the centre
  /// sees without crossing an obstacle cell become floor. Obstacle cells stay obstacles.
  void addKnownFree(const Eigen::Vector2d& center_map, double radius_m);

  /// Cell states (CV_8U, CellState values) with geometry(), after the gap filling.
  cv::Mat states() const;
  const GridGeometry& geometry() const { return geometry_; }
  const FloorConfig& config() const { return config_; }
  bool empty() const { return geometry_.width == 0; }

  /// Grows the grid (never shrinks) so that the map-frame box [lo, hi] plus margin fits.
  void ensureContains(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

 private:
  FloorConfig config_;
  GridGeometry geometry_;
  cv::Mat floor_hits_;     ///< CV_32S
  cv::Mat obstacle_hits_;  ///< CV_32S: scans that made the cell an obstacle
  cv::Mat obstacle_max_;   ///< CV_32S: most obstacle-layer points one scan put into the cell
  cv::Mat obstacle_seen_;  ///< CV_32S: scans that put at least one obstacle-layer point into the cell
  std::vector<std::pair<Eigen::Vector2d, double>> known_free_;  ///< discs (centre [m], radius [m])
};

}  // namespace explorer
}  // namespace scanstop
