#include "scanstop_mesher/spatial_grid.h"

#include <algorithm>
#include <limits>

namespace scanstop {
namespace mesher {

SpatialGrid::SpatialGrid(const std::vector<Eigen::Vector3d>& points, double cell_m) : points_(points) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  size_t finite = 0;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    ++finite;
  }
  if (finite == 0) return;
  origin_ = lo;
  const Eigen::Vector3d extent = hi - lo;
  cell_ = cell_m > 0 && std::isfinite(cell_m) ? cell_m : 1.0;
  // Memory bound: at most 4 * points + 1 cells; enlarge the cells until that holds.
  const double max_cells = 4.0 * static_cast<double>(finite) + 1.0;
  for (;;) {
    double cells = 1.0;
    for (int d = 0; d < 3; ++d) cells *= std::floor(extent[d] / cell_) + 1.0;
    if (cells <= max_cells) break;
    cell_ *= 1.25;
  }
  for (int d = 0; d < 3; ++d) dims_[d] = static_cast<int>(std::floor(extent[d] / cell_)) + 1;
  const size_t num_cells = static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2];
  std::vector<uint32_t> cell_of(points.size(), std::numeric_limits<uint32_t>::max());
  start_.assign(num_cells + 1, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) continue;
    int c[3];
    for (int d = 0; d < 3; ++d)
      c[d] = std::min(dims_[d] - 1, static_cast<int>(std::floor((points[i][d] - origin_[d]) / cell_)));
    cell_of[i] = static_cast<uint32_t>((static_cast<size_t>(c[2]) * dims_[1] + c[1]) * dims_[0] + c[0]);
    ++start_[cell_of[i] + 1];
  }
  for (size_t c = 0; c < num_cells; ++c) start_[c + 1] += start_[c];
  order_.resize(finite);
  std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < points.size(); ++i)
    if (cell_of[i] != std::numeric_limits<uint32_t>::max()) order_[fill[cell_of[i]]++] = static_cast<uint32_t>(i);
}

}  // namespace mesher
}  // namespace scanstop
