#include "scanstop_eval/surface_elements.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace scanstop {
namespace eval {

namespace {

bool isSurface(const TriangleMesh& mesh, const Eigen::Vector3i& f, double z_lo) {
  return std::max({mesh.vertices[f[0]].z(), mesh.vertices[f[1]].z(), mesh.vertices[f[2]].z()}) >= z_lo;
}

}  // namespace

SurfaceElements::SurfaceElements(const TriangleMesh& mesh, double cell_m, double z_lo, double max_cells) {
  if (!(cell_m > 0.0)) throw std::invalid_argument("surface elements: the cell must be > 0 m");
  cell_ = static_cast<float>(cell_m);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
  for (const Eigen::Vector3i& f : mesh.faces)
    if (isSurface(mesh, f, z_lo))
      for (int k = 0; k < 3; ++k) {
        lo = lo.cwiseMin(mesh.vertices[f[k]]);
        hi = hi.cwiseMax(mesh.vertices[f[k]]);
      }
  if (lo.x() > hi.x()) return;  // nothing but floor
  origin_ = lo - Eigen::Vector3f::Constant(cell_);
  double cells = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double n = std::ceil((hi[a] - origin_[a]) / cell_m) + 2.0;
    cells *= n;
    dims_[a] = static_cast<int>(std::min(n, 1e9));
  }
  if (cells > max_cells) {
    std::ostringstream what;
    what << "surface elements: the surface's bounding box (" << (hi - lo).transpose() << " m) needs " << cells
         << " cubes of " << cell_m << " m, more than the limit of " << max_cells << " (a coarser surface cell)";
    throw std::length_error(what.str());
  }
  grid_.assign(static_cast<size_t>(cells), -1);
  const float step = cell_ / 2.0f;
  for (const Eigen::Vector3i& f : mesh.faces) {
    if (!isSurface(mesh, f, z_lo)) continue;
    const Eigen::Vector3f& a = mesh.vertices[f[0]];
    const Eigen::Vector3f ab = mesh.vertices[f[1]] - a, ac = mesh.vertices[f[2]] - a;
    const float longest = std::max({ab.norm(), ac.norm(), (ac - ab).norm()});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / step)));
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j)
        addSample(a + (static_cast<float>(i) / n) * ab + (static_cast<float>(j) / n) * ac);
  }
}

void SurfaceElements::addSample(const Eigen::Vector3f& p) {
  int c[3];
  for (int a = 0; a < 3; ++a)
    c[a] = std::clamp(static_cast<int>(std::floor((p[a] - origin_[a]) / cell_)), 0, dims_[a] - 1);
  const Eigen::Vector3f centre =
      origin_ + (Eigen::Vector3f(c[0], c[1], c[2]) + Eigen::Vector3f::Constant(0.5f)) * cell_;
  const float d2 = (p - centre).squaredNorm();
  int32_t& id = grid_[index(c[0], c[1], c[2])];
  if (id < 0) {
    id = static_cast<int32_t>(points_.size());
    points_.push_back(p);
    centre_distance2_.push_back(d2);
  } else if (d2 < centre_distance2_[id]) {
    points_[id] = p;
    centre_distance2_[id] = d2;
  }
}

}  // namespace eval
}  // namespace scanstop
