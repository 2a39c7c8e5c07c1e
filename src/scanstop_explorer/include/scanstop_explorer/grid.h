#pragma once
/// Geometry of the explorer's 2D grids: cell (col, row) <-> map-frame coordinates.
///
/// Every explorer grid is a cv::Mat with rows along +y and columns along +x of the map frame:
/// row 0 is the lowest y, exactly the row order of nav_msgs/OccupancyGrid data.

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace scanstop {
namespace explorer {

/// Placement of a grid in the map frame.
struct GridGeometry {
  double origin_x = 0.0;     ///< x of the lower-left corner of cell (0, 0) [m]
  double origin_y = 0.0;     ///< y of the lower-left corner of cell (0, 0) [m]
  double resolution = 0.05;  ///< cell edge [m]
  int width = 0;             ///< columns (x)
  int height = 0;            ///< rows (y)

  bool contains(const cv::Point& cell) const { return cell.x >= 0 && cell.y >= 0 && cell.x < width && cell.y < height; }
  /// The cell holding map point (x, y) [m] (may lie outside the grid).
  cv::Point cellOf(double x_m, double y_m) const;
  /// Centre of a cell in the map frame [m].
  Eigen::Vector2d center(const cv::Point& cell) const {
    return {origin_x + (cell.x + 0.5) * resolution, origin_y + (cell.y + 0.5) * resolution};
  }
  /// Continuous cell coordinates (cell (c, r) spans [c, c+1) x [r, r+1)) of a map point.
  Eigen::Vector2d toGrid(const Eigen::Vector2d& p_map) const {
    return {(p_map.x() - origin_x) / resolution, (p_map.y() - origin_y) / resolution};
  }
  cv::Size size() const { return {width, height}; }
  double cellArea() const { return resolution * resolution; }
};

}  // namespace explorer
}  // namespace scanstop
