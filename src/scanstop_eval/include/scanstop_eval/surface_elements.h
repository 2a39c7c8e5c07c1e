#pragma once
/// The world's surface as small elements: every triangle that is not floor, sampled and binned into
/// cubic cells; one element per occupied cell, represented by the sample nearest the cell's centre.
/// A scan sees an element when one of its points lies within a tolerance of that representative.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "scanstop_common/cloud.h"

namespace scanstop {
namespace eval {

class SurfaceElements {
 public:
  /// Samples the mesh's triangles that reach z_lo or higher (the floor below z_lo is left out) every
  /// cell_m / 2 and bins the samples into cubes of cell_m [m]. Throws std::invalid_argument for a
  /// cell <= 0 and std::length_error when the cube grid over the surface's bounding box would exceed
  /// max_cells (4 bytes each).
  SurfaceElements(const TriangleMesh& mesh, double cell_m, double z_lo, double max_cells = 2e8);

  size_t size() const { return points_.size(); }
  /// Representative point of element i (world frame) [m].
  const Eigen::Vector3f& point(size_t i) const { return points_[i]; }
  double cell() const { return cell_; }

  /// Calls f(id) for every element whose representative lies within tolerance_m of p [m]
  /// (tolerance_m at most cell_m, so only the neighbouring cubes are searched).
  template <class F>
  void forEachNear(const Eigen::Vector3f& p, float tolerance_m, F&& f) const {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, static_cast<int>(std::floor((p[a] - tolerance_m - origin_[a]) / cell_)));
      hi[a] = std::min(dims_[a] - 1, static_cast<int>(std::floor((p[a] + tolerance_m - origin_[a]) / cell_)));
    }
    const float tol2 = tolerance_m * tolerance_m;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const int32_t id = grid_[index(x, y, z)];
          if (id >= 0 && (points_[id] - p).squaredNorm() <= tol2) f(static_cast<uint32_t>(id));
        }
  }

 private:
  size_t index(int x, int y, int z) const {
    return (static_cast<size_t>(z) * dims_[1] + static_cast<size_t>(y)) * dims_[0] + static_cast<size_t>(x);
  }
  void addSample(const Eigen::Vector3f& p);

  float cell_ = 0.05f;
  Eigen::Vector3f origin_ = Eigen::Vector3f::Zero();
  int dims_[3] = {0, 0, 0};
  std::vector<int32_t> grid_;            ///< cube -> element id, -1 empty
  std::vector<Eigen::Vector3f> points_;  ///< representative per element
  std::vector<float> centre_distance2_;  ///< its squared distance to the cube's centre
};

}  // namespace eval
}  // namespace scanstop
