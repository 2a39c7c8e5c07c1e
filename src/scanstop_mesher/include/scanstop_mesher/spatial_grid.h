#pragma once
/// A uniform spatial grid over a fixed point set for radius queries (thesis 7.4: "we subdivide
/// the space into a regular grid"). Points are sorted by cell (counting sort), so memory is linear
/// in the points: one index per point plus at most 4 * points + 1 cell offsets (the cell size is
/// enlarged when the requested one would need more cells).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

namespace scanstop {
namespace mesher {

/// Morton code (bits interleaved x, y, z) of cell coordinates below 2^21: sorting by it keeps
/// nearby cells close in memory.
inline uint64_t mortonCode(uint64_t x, uint64_t y, uint64_t z) {
  auto spread = [](uint64_t v) {  // the 21 low bits of v at every third position
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

class SpatialGrid {
 public:
  /// Builds the grid over points (kept by reference: they must outlive the grid) with cells of at
  /// least cell_m [m]. Non-finite points are left out.
  SpatialGrid(const std::vector<Eigen::Vector3d>& points, double cell_m);

  double cellSize() const { return cell_; }

  /// Calls f(index) for every point within radius_m (inclusive) of center.
  template <typename F>
  void forEachWithin(const Eigen::Vector3d& center, double radius_m, F&& f) const {
    forEachPointWithin(center, radius_m, [&f](uint32_t idx, const Eigen::Vector3d&) { f(idx); });
  }

  /// Calls f(index, point) for every point within radius_m (inclusive) of center.
  template <typename F>
  void forEachPointWithin(const Eigen::Vector3d& center, double radius_m, F&& f) const {
    if (order_.empty()) return;
    const double r2 = radius_m * radius_m;
    int lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
      const double a = std::floor((center[d] - radius_m - origin_[d]) / cell_);
      const double b = std::floor((center[d] + radius_m - origin_[d]) / cell_);
      if (b < 0 || a >= dims_[d]) return;
      lo[d] = a < 0 ? 0 : static_cast<int>(a);
      hi[d] = b >= dims_[d] ? dims_[d] - 1 : static_cast<int>(b);
    }
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y) {
        const size_t row = (static_cast<size_t>(z) * dims_[1] + y) * dims_[0];
        const uint32_t begin = start_[row + lo[0]], end = start_[row + hi[0] + 1];
        for (uint32_t k = begin; k < end; ++k) {
          const uint32_t idx = order_[k];
          const Eigen::Vector3d& p = points_[idx];
          if ((p - center).squaredNorm() <= r2) f(idx, p);
        }
      }
  }

  /// Indices of the points within radius_m of center (appended to out after clearing it).
  void within(const Eigen::Vector3d& center, double radius_m, std::vector<uint32_t>& out) const {
    out.clear();
    forEachWithin(center, radius_m, [&out](uint32_t i) { out.push_back(i); });
  }

  /// Point indices in cell order (spatially coherent), finite points only.
  const std::vector<uint32_t>& cellOrder() const { return order_; }
  /// Number of cells; the points of cell c are cellOrder()[cellBegin(c) .. cellBegin(c + 1)).
  size_t numCells() const { return start_.empty() ? 0 : start_.size() - 1; }
  uint32_t cellBegin(size_t c) const { return start_[c]; }

 private:
  const std::vector<Eigen::Vector3d>& points_;
  double cell_ = 1.0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  int dims_[3] = {0, 0, 0};
  std::vector<uint32_t> start_;  ///< per cell (x fastest) the first position in order_; one extra at the end
  std::vector<uint32_t> order_;
};

}  // namespace mesher
}  // namespace scanstop
