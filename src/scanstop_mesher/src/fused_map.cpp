#include "scanstop_mesher/fused_map.h"

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <unordered_map>
#include <utility>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/mesh_analysis.h"

namespace scanstop {
namespace mesher {

struct FusedMap::Grids {
  openvdb::FloatGrid::Ptr tsdf;    ///< signed distance [m]; background +truncation (never updated)
  openvdb::FloatGrid::Ptr weight;  ///< readings per voxel (capped); background 0
};

namespace {

using Coord = openvdb::Coord;
using ConstAccessor = openvdb::FloatGrid::ConstAccessor;
using Leaf = openvdb::FloatTree::LeafNodeType;

double elapsed(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Amanatides-Woo over the unit cells of q from q = a to q = b: visit(cell, s0, s1) for each cell the
/// segment crosses, [s0, s1] the segment's parameter range in it (0 at a, 1 at b), in order.
template <class Visit>
void walkCells(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Visit visit) {
  const Eigen::Vector3d d = b - a;
  Eigen::Vector3i cell(static_cast<int>(std::floor(a.x())), static_cast<int>(std::floor(a.y())),
                       static_cast<int>(std::floor(a.z())));
  const Eigen::Vector3i end(static_cast<int>(std::floor(b.x())), static_cast<int>(std::floor(b.y())),
                            static_cast<int>(std::floor(b.z())));
  Eigen::Vector3i step;
  Eigen::Vector3d t_max, t_delta;
  for (int k = 0; k < 3; ++k) {
    step[k] = d[k] > 0 ? 1 : -1;
    if (std::abs(d[k]) < 1e-12) {
      t_max[k] = t_delta[k] = INFINITY;
    } else {
      t_delta[k] = 1.0 / std::abs(d[k]);
      t_max[k] = ((d[k] > 0 ? cell[k] + 1 : cell[k]) - a[k]) / d[k];
    }
  }
  const long max_steps = (end - cell).cwiseAbs().sum() + 4;
  double s = 0.0;
  for (long n = 0; n <= max_steps; ++n) {
    int k = 0;
    if (t_max[1] < t_max[k]) k = 1;
    if (t_max[2] < t_max[k]) k = 2;
    visit(cell, s, std::min(1.0, t_max[k]));
    if (cell == end || t_max[k] > 1.0) break;
    s = t_max[k];
    cell[k] += step[k];
    t_max[k] += t_delta[k];
  }
}

/// The 8 corner values of the cell between voxels c and c + (1,1,1); corner index bits: x = 1,
/// y = 2, z = 4. False when a corner is not observed.
bool loadCell(const ConstAccessor& tsdf, const ConstAccessor& weight, const Coord& c, float min_weight, float v[8]) {
  for (int k = 0; k < 8; ++k) {
    const Coord q(c.x() + (k & 1), c.y() + ((k >> 1) & 1), c.z() + ((k >> 2) & 1));
    if (weight.getValue(q) < min_weight) return false;
    v[k] = tsdf.getValue(q);
  }
  return true;
}

/// True when the cell's corner values change sign (a value of 0 counts as positive).
bool hasCrossing(const float v[8]) {
  bool neg = false, pos = false;
  for (int k = 0; k < 8; ++k) (v[k] < 0.0f ? neg : pos) = true;
  return neg && pos;
}

/// The cell's trilinear field at local coordinates x in [0,1]^3, and its gradient [m per voxel].
double trilinear(const float v[8], const Eigen::Vector3d& x, Eigen::Vector3d* gradient) {
  double f = 0.0;
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int k = 0; k < 8; ++k) {
    double w[3], dw[3];
    for (int a = 0; a < 3; ++a) {
      const bool hi = (k >> a) & 1;
      w[a] = hi ? x[a] : 1.0 - x[a];
      dw[a] = hi ? 1.0 : -1.0;
    }
    f += v[k] * w[0] * w[1] * w[2];
    g.x() += v[k] * dw[0] * w[1] * w[2];
    g.y() += v[k] * w[0] * dw[1] * w[2];
    g.z() += v[k] * w[0] * w[1] * dw[2];
  }
  if (gradient) *gradient = g;
  return f;
}

/// The mean of the cell's edge crossings (linear interpolation along each of the 12 edges with a
/// sign change), in local coordinates.
Eigen::Vector3d meanCrossing(const float v[8]) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (int a = 0; a < 8; ++a) {
    for (int axis = 0; axis < 3; ++axis) {
      if ((a >> axis) & 1) continue;
      const int b = a | (1 << axis);
      if ((v[a] < 0.0f) == (v[b] < 0.0f)) continue;
      const double f = static_cast<double>(v[a]) / (static_cast<double>(v[a]) - static_cast<double>(v[b]));
      Eigen::Vector3d p(a & 1, (a >> 1) & 1, (a >> 2) & 1);
      p[axis] = f;
      sum += p;
      ++n;
    }
  }
  return n > 0 ? Eigen::Vector3d(sum / n) : Eigen::Vector3d::Constant(0.5);
}

std::string vecText(const Eigen::Vector3f& p) {
  std::ostringstream s;
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

}  // namespace

void FusedMapConfig::validate() const {
  requireInRange("voxel_m", voxel_m, 0.001, 1.0, "m");
  requireInRange("truncation_m", truncation_m, 2.0 * voxel_m, 1.0, "m");
  requireInRange("carve_m", carve_m, 0.0, 1000.0, "m");
  requireInRange("splat", splat, 0, 3, "voxels");
  requireInRange("max_weight", max_weight, 1.0, 1e6);
  requireInRange("min_weight", min_weight, 1.0, max_weight);
  requireInRange("max_grid_mb", max_grid_mb, 1.0, 1e6, "MB");
  requireInRange("threads", threads, 1, 16);
  if (clip_x_min_voxel > clip_x_max_voxel)
    throw ConfigError("clip_x_min_voxel = " + std::to_string(clip_x_min_voxel) +
                      " is above clip_x_max_voxel = " + std::to_string(clip_x_max_voxel));
}

FusedMap::FusedMap(const FusedMapConfig& config) : config_(config), grids_(new Grids) {
  config_.validate();
  openvdb::initialize();
  const auto transform = openvdb::math::Transform::createLinearTransform(config_.voxel_m);
  grids_->tsdf = openvdb::FloatGrid::create(static_cast<float>(config_.truncation_m));
  grids_->tsdf->setTransform(transform);
  grids_->tsdf->setName("tsdf");
  grids_->tsdf->setGridClass(openvdb::GRID_UNKNOWN);
  grids_->weight = openvdb::FloatGrid::create(0.0f);
  grids_->weight->setTransform(transform->copy());
  grids_->weight->setName("weight");
}

FusedMap::~FusedMap() = default;
FusedMap::FusedMap(FusedMap&&) noexcept = default;
FusedMap& FusedMap::operator=(FusedMap&&) noexcept = default;

size_t FusedMap::integrate(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin) {
  return integrateSigned(points, origin, false);
}

size_t FusedMap::deintegrate(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin) {
  return integrateSigned(points, origin, true);
}

size_t FusedMap::integrateSigned(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin,
                                 bool remove) {
  if (!origin.allFinite()) throw ConfigError("sensor origin " + vecText(origin) + " is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Accessor tsdf = grids_->tsdf->getAccessor();
  openvdb::FloatGrid::Accessor weight = grids_->weight->getAccessor();
  const double vs = config_.voxel_m, trunc = config_.truncation_m;
  const float max_w = static_cast<float>(config_.max_weight);
  const Eigen::Vector3d o = origin.cast<double>();
  size_t used = 0, updates = 0;
  const int clip_lo = config_.clip_x_min_voxel, clip_hi = config_.clip_x_max_voxel;
  const bool clipped = clip_lo != std::numeric_limits<int>::min() || clip_hi != std::numeric_limits<int>::max();
  // Both grids get a leaf node at the same place: the bound counts their leaves as they are allocated
  // (a Leaf: the node and its separately allocated voxel buffer).
  const double leaf_bytes = 2.0 * (sizeof(Leaf) + Leaf::SIZE * sizeof(float));
  const size_t max_leaves = static_cast<size_t>(bound_share_ * config_.max_grid_mb * 1048576.0 / leaf_bytes);
  Leaf* tsdf_leaf = nullptr;
  Leaf* weight_leaf = nullptr;
  Coord cached_origin(std::numeric_limits<int>::min(), 0, 0);  // no leaf's origin (those are multiples of 8)
  for (const Eigen::Vector3f& pf : points) {
    if (!pf.allFinite()) {
      ++stats_.skipped_points;
      continue;
    }
    Eigen::Vector3d dir = pf.cast<double>() - o;
    const double r = dir.norm();
    if (r < 1e-6) {
      ++stats_.skipped_points;
      continue;
    }
    dir /= r;
    ++used;
    const int splat = config_.splat;
    // Thin traversal: the whole beam (splat 0), else only the carved part before the band.
    const double t0_beam = std::max(0.0, r - trunc - config_.carve_m), t1_beam = splat > 0 ? r - trunc : r + trunc;
    if (clipped) {  // a beam whose voxels all lie outside the slab (a voxel of margin, and the splat) is skipped
      const double xa = (o.x() + t0_beam * dir.x()) / vs, xb = (o.x() + (r + trunc) * dir.x()) / vs;
      if (std::max(xa, xb) + 2 + splat < clip_lo || std::min(xa, xb) - 2 - splat > clip_hi) continue;
    }
    const auto update = [&](const Coord& c, double sdf) {
      if (c.x() < clip_lo || c.x() > clip_hi) return;                // another slab's voxel
      const float value = static_cast<float>(std::min(sdf, trunc));  // before the band: free (+trunc)
      // The voxels of a beam come leaf by leaf: the two leaves' buffers directly while in one
      // (the accessors' lookups per voxel took most of the integration's time).
      const Coord leaf_origin(c.x() & ~7, c.y() & ~7, c.z() & ~7);
      if (remove) {  // the reading's update taken back: nothing is created
        if (leaf_origin != cached_origin) {
          weight_leaf = weight.probeLeaf(c);
          tsdf_leaf = tsdf.probeLeaf(c);
          cached_origin = leaf_origin;
        }
        if (!weight_leaf || !tsdf_leaf) return;
        const openvdb::Index at = Leaf::coordToOffset(c);
        const float w = weight_leaf->getValue(at);
        if (w <= 0.0f) return;
        if (w <= 1.0f) {  // its only reading: the voxel was never seen
          tsdf_leaf->setValueOff(at, static_cast<float>(trunc));
          weight_leaf->setValueOff(at, 0.0f);
        } else {
          tsdf_leaf->setValueOn(at, (tsdf_leaf->getValue(at) * w - value) / (w - 1.0f));
          weight_leaf->setValueOn(at, w - 1.0f);
        }
        ++updates;
        return;
      }
      if (leaf_origin != cached_origin) {
        weight_leaf = weight.probeLeaf(c);
        if (!weight_leaf && ++stats_.leaves_created > max_leaves) {
          std::ostringstream o;
          o << "the fused map's grids passed max_grid_mb = " << config_.max_grid_mb << " MB (" << stats_.leaves_created
            << " leaf nodes of 8^3 voxels) after " << used << " of scan " << stats_.scans + 1 << "'s " << points.size()
            << " readings: voxel_m = " << config_.voxel_m
            << " m is too fine for the mapped space; use a larger voxel (default 0.02 m) or raise max_grid_mb";
          throw GridBoundError(o.str());
        }
        if (!weight_leaf) weight_leaf = weight.touchLeaf(c);
        tsdf_leaf = tsdf.touchLeaf(c);
        cached_origin = leaf_origin;
      }
      const openvdb::Index at = Leaf::coordToOffset(c);
      const float w = weight_leaf->getValue(at);
      const float D = w > 0.0f ? tsdf_leaf->getValue(at) : 0.0f;
      tsdf_leaf->setValueOn(at, (D * w + value) / (w + 1.0f));
      weight_leaf->setValueOn(at, std::min(w + 1.0f, max_w));
      ++updates;
    };
    if (splat > 0) {
      // The band in slices across the main axis m: the beam's voxel in each slice and its neighbours.
      int m = 0;
      if (std::abs(dir[1]) > std::abs(dir[m])) m = 1;
      if (std::abs(dir[2]) > std::abs(dir[m])) m = 2;
      const int n1 = (m + 1) % 3, n2 = (m + 2) % 3;
      const double ua = (o[m] + (r - trunc) * dir[m]) / vs, ub = (o[m] + (r + trunc) * dir[m]) / vs;
      const long s0 = std::lround(std::min(ua, ub)), s1 = std::lround(std::max(ua, ub));
      for (long sl = s0; sl <= s1; ++sl) {
        const double t = (sl * vs - o[m]) / dir[m];  // the beam crosses the slice's centre plane
        const long c1 = std::lround((o[n1] + t * dir[n1]) / vs), c2 = std::lround((o[n2] + t * dir[n2]) / vs);
        for (long i1 = c1 - splat; i1 <= c1 + splat; ++i1) {
          for (long i2 = c2 - splat; i2 <= c2 + splat; ++i2) {
            Eigen::Vector3i v;
            v[m] = static_cast<int>(sl);
            v[n1] = static_cast<int>(i1);
            v[n2] = static_cast<int>(i2);
            const double sdf = r - (v.cast<double>() * vs - o).dot(dir);
            if (sdf < -trunc || sdf > trunc) continue;
            update(Coord(v.x(), v.y(), v.z()), sdf);
          }
        }
      }
      if (config_.carve_m <= 0.0) continue;
    }
    // Amanatides-Woo traversal in u = x / voxel + 0.5, where voxel(u) = floor(u).
    const Eigen::Vector3d a = (o + t0_beam * dir) / vs + Eigen::Vector3d::Constant(0.5);
    const Eigen::Vector3d b = (o + t1_beam * dir) / vs + Eigen::Vector3d::Constant(0.5);
    walkCells(a, b, [&](const Eigen::Vector3i& ijk, double, double) {
      const double sdf = r - (ijk.cast<double>() * vs - o).dot(dir);  // along the beam, positive in front of the hit
      // With splat the band is done above: here only the free part.
      if (sdf >= -trunc && (splat == 0 || sdf > trunc)) update(Coord(ijk.x(), ijk.y(), ijk.z()), sdf);
    });
  }
  if (remove) {
    stats_.scans -= std::min<size_t>(stats_.scans, 1);
    stats_.points -= std::min(stats_.points, used);
  } else {
    ++stats_.scans;
    stats_.points += used;
  }
  stats_.voxel_updates += updates;
  stats_.integrate_seconds += elapsed(t0);
  return used;
}

namespace {

/// The leaves of the field with a voxel nearer a surface than the truncation (a distance below it):
/// the far pass walks only these. A free update leaves a voxel at +truncation where it is, so in a
/// leaf of free voxels it would change weights alone, and no surface cell has its corners there.
openvdb::BoolGrid::Ptr bandLeaves(const openvdb::FloatGrid& tsdf, float truncation) {
  openvdb::BoolGrid::Ptr band = openvdb::BoolGrid::create(false);
  openvdb::BoolGrid::Accessor acc = band->getAccessor();
  for (auto it = tsdf.tree().cbeginLeaf(); it; ++it)
    for (auto v = it->cbeginValueOn(); v; ++v)
      if (*v < truncation) {
        acc.touchLeaf(it->origin());
        break;
      }
  return band;
}

/// The far carving pass's walk of one scan (FusedMapConfig::carve_far): for every voxel farther than
/// truncation_m + carve_m before a beam's hit that exists in `weight` (weight above 0), in its slab,
/// apply(leaf origin, offset in the leaf). Beams skip the leaves that do not exist. Returns the calls.
template <class Apply>
size_t walkFar(const openvdb::FloatGrid& weight_grid, const openvdb::BoolGrid& band_grid, const FusedMapConfig& config,
               const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin, Apply apply) {
  ConstAccessor weight = weight_grid.getConstAccessor();
  openvdb::BoolGrid::ConstAccessor band = band_grid.getConstAccessor();
  const double vs = config.voxel_m, near = config.truncation_m + config.carve_m;
  const int clip_lo = config.clip_x_min_voxel, clip_hi = config.clip_x_max_voxel;
  const Eigen::Vector3d o = origin.cast<double>();
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5);
  size_t updates = 0;
  constexpr int kLeaf = 8;  // voxels per leaf edge (OpenVDB's FloatTree)
  for (const Eigen::Vector3f& pf : points) {
    if (!pf.allFinite()) continue;
    Eigen::Vector3d dir = pf.cast<double>() - o;
    const double r = dir.norm();
    if (!(r > near)) continue;
    dir /= r;
    // In voxel units u = x / voxel + 0.5 (voxel(u) = floor(u)); leaves are 8 voxels: floor(u / 8).
    const Eigen::Vector3d ua = o / vs + half, ub = (o + (r - near) * dir) / vs + half;
    walkCells(ua / kLeaf, ub / kLeaf, [&](const Eigen::Vector3i& leaf, double s0, double s1) {
      const Coord leaf_origin(leaf.x() * kLeaf, leaf.y() * kLeaf, leaf.z() * kLeaf);
      if (!band.probeConstLeaf(leaf_origin)) return;  // no voxel near a surface in this leaf
      const Leaf* const weight_leaf = weight.probeConstLeaf(leaf_origin);
      if (!weight_leaf) return;
      walkCells(ua + s0 * (ub - ua), ua + s1 * (ub - ua), [&](const Eigen::Vector3i& v, double, double) {
        if (v.x() < clip_lo || v.x() > clip_hi) return;
        if (Eigen::Vector3i(v.x() >> 3, v.y() >> 3, v.z() >> 3) != leaf) return;  // the next leaf's: its own turn
        const openvdb::Index at = Leaf::coordToOffset(Coord(v.x(), v.y(), v.z()));
        if (weight_leaf->getValue(at) == 0.0f) return;                 // no voxel here: none is made
        if (r - (v.cast<double>() * vs - o).dot(dir) <= near) return;  // integrate() carved it
        apply(leaf_origin, at);
        ++updates;
      });
    });
  }
  return updates;
}

/// n free (+truncation) updates of a voxel at once: the running average's n steps in one.
inline void freeUpdates(Leaf* tsdf_leaf, Leaf* weight_leaf, openvdb::Index at, float n, float free_value, float max_w) {
  const float w = weight_leaf->getValue(at);
  const float D = tsdf_leaf->getValue(at);
  tsdf_leaf->setValueOn(at, (D * w + free_value * n) / (w + n));
  weight_leaf->setValueOn(at, std::min(w + n, max_w));
}

}  // namespace

void runInThreads(int threads, const std::function<void(int)>& work) {
  std::vector<std::exception_ptr> failed(threads);
  const auto guarded = [&](int t) {
    try {
      work(t);
    } catch (...) {
      failed[t] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(guarded, t);
  guarded(0);
  for (std::thread& th : pool) th.join();
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

size_t FusedMap::carveFar(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin) {
  if (!origin.allFinite()) throw ConfigError("sensor origin " + vecText(origin) + " is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Accessor tsdf = grids_->tsdf->getAccessor();
  openvdb::FloatGrid::Accessor weight = grids_->weight->getAccessor();
  const float max_w = static_cast<float>(config_.max_weight), free_value = static_cast<float>(config_.truncation_m);
  Leaf* tsdf_leaf = nullptr;
  Leaf* weight_leaf = nullptr;
  Coord cached(std::numeric_limits<int>::min(), 0, 0);
  const openvdb::BoolGrid::Ptr band = bandLeaves(*grids_->tsdf, static_cast<float>(config_.truncation_m));
  const size_t updates =
      walkFar(*grids_->weight, *band, config_, points, origin, [&](const Coord& leaf, openvdb::Index at) {
        if (leaf != cached) {
          weight_leaf = weight.probeLeaf(leaf);
          tsdf_leaf = tsdf.touchLeaf(leaf);  // exists with the weight's (integrate())
          cached = leaf;
        }
        freeUpdates(tsdf_leaf, weight_leaf, at, 1.0f, free_value, max_w);
      });
  stats_.voxel_updates += updates;
  stats_.integrate_seconds += elapsed(t0);
  return updates;
}

void FusedMap::carveFarAll(size_t scans, const ScanLoader& load, int threads) {
  const auto t0 = std::chrono::steady_clock::now();
  threads = static_cast<int>(std::min<size_t>(std::max(1, threads), std::max<size_t>(scans, 1)));
  const auto first = [&](int t) { return scans * static_cast<size_t>(t) / static_cast<size_t>(threads); };
  // Each thread counts its free updates per voxel in a grid of its own (the field stays as it is
  // while they walk); the counts are added at the end.
  std::vector<openvdb::FloatGrid::Ptr> counts(threads);
  std::vector<size_t> updates(threads, 0);
  const openvdb::BoolGrid::Ptr band = bandLeaves(*grids_->tsdf, static_cast<float>(config_.truncation_m));
  runInThreads(threads, [&](int t) {
    counts[t] = openvdb::FloatGrid::create(0.0f);
    openvdb::FloatGrid::Accessor count = counts[t]->getAccessor();
    Leaf* count_leaf = nullptr;
    Coord cached(std::numeric_limits<int>::min(), 0, 0);
    std::vector<Eigen::Vector3f> points;
    Eigen::Vector3f origin;
    for (size_t s = first(t); s < first(t + 1); ++s) {
      if (!load(s, points, origin)) continue;
      updates[t] += walkFar(*grids_->weight, *band, config_, points, origin, [&](const Coord& leaf, openvdb::Index at) {
        if (leaf != cached) {
          count_leaf = count.touchLeaf(leaf);
          cached = leaf;
        }
        count_leaf->setValueOn(at, count_leaf->getValue(at) + 1.0f);
      });
    }
  });
  openvdb::FloatGrid::Accessor tsdf = grids_->tsdf->getAccessor();
  openvdb::FloatGrid::Accessor weight = grids_->weight->getAccessor();
  const float max_w = static_cast<float>(config_.max_weight);
  const float free_value = static_cast<float>(config_.truncation_m);
  for (int t = 0; t < threads; ++t) {
    for (auto it = counts[t]->tree().cbeginLeaf(); it; ++it) {
      Leaf* const tsdf_leaf = tsdf.probeLeaf(it->origin());
      Leaf* const weight_leaf = weight.probeLeaf(it->origin());
      for (auto v = it->cbeginValueOn(); v; ++v) freeUpdates(tsdf_leaf, weight_leaf, v.pos(), *v, free_value, max_w);
    }
    counts[t].reset();
    stats_.voxel_updates += updates[t];
  }
  stats_.integrate_seconds += elapsed(t0);
}

FusedMap FusedMap::copy() const {
  FusedMap out(config_);
  out.grids_->tsdf = grids_->tsdf->deepCopy();
  out.grids_->weight = grids_->weight->deepCopy();
  out.stats_ = stats_;
  out.bound_share_ = bound_share_;
  return out;
}

void FusedMap::merge(const FusedMap& other) {
  if (other.config_.voxel_m != config_.voxel_m || other.config_.truncation_m != config_.truncation_m)
    throw ConfigError("cannot merge a fused map of voxel " + std::to_string(other.config_.voxel_m) + " m, truncation " +
                      std::to_string(other.config_.truncation_m) + " m into one of voxel " +
                      std::to_string(config_.voxel_m) + " m, truncation " + std::to_string(config_.truncation_m) +
                      " m");
  const auto t0 = std::chrono::steady_clock::now();
  openvdb::FloatGrid::Accessor tsdf = grids_->tsdf->getAccessor();
  openvdb::FloatGrid::Accessor weight = grids_->weight->getAccessor();
  ConstAccessor other_tsdf = other.grids_->tsdf->getConstAccessor();
  const float max_w = static_cast<float>(config_.max_weight);
  const double leaf_bytes = 2.0 * (sizeof(Leaf) + Leaf::SIZE * sizeof(float));
  const size_t max_leaves = static_cast<size_t>(bound_share_ * config_.max_grid_mb * 1048576.0 / leaf_bytes);
  for (auto it = other.grids_->weight->tree().cbeginLeaf(); it; ++it) {
    const Leaf& other_weight = *it;
    const Coord origin = other_weight.origin();
    const Leaf* const other_tsdf_leaf = other_tsdf.probeConstLeaf(origin);
    Leaf* weight_leaf = weight.probeLeaf(origin);
    if (!weight_leaf) {
      if (++stats_.leaves_created > max_leaves)
        throw GridBoundError("the fused map's grids passed max_grid_mb = " + std::to_string(config_.max_grid_mb) +
                             " MB (" + std::to_string(stats_.leaves_created) +
                             " leaf nodes of 8^3 voxels) while merging the threads' grids: voxel_m = " +
                             std::to_string(config_.voxel_m) + " m is too fine for the mapped space");
      weight_leaf = weight.touchLeaf(origin);
    }
    Leaf* const tsdf_leaf = tsdf.touchLeaf(origin);
    for (auto v = other_weight.cbeginValueOn(); v; ++v) {
      const openvdb::Index at = v.pos();
      const float w2 = *v;
      if (w2 <= 0.0f) continue;
      const float D2 = other_tsdf_leaf ? other_tsdf_leaf->getValue(at) : static_cast<float>(config_.truncation_m);
      const float w1 = weight_leaf->getValue(at);
      const float D1 = w1 > 0.0f ? tsdf_leaf->getValue(at) : 0.0f;
      tsdf_leaf->setValueOn(at, (D1 * w1 + D2 * w2) / (w1 + w2));
      weight_leaf->setValueOn(at, std::min(w1 + w2, max_w));
    }
  }
  stats_.scans += other.stats_.scans;
  stats_.points += other.stats_.points;
  stats_.skipped_points += other.stats_.skipped_points;
  stats_.voxel_updates += other.stats_.voxel_updates;
  stats_.integrate_seconds += elapsed(t0);
}

ScanPoints FusedMap::surfacePoints() const {
  return surfacePoints(std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
}

ScanPoints FusedMap::surfacePoints(int cell_x_min, int cell_x_max) const {
  const ConstAccessor tsdf = grids_->tsdf->getConstAccessor();
  const ConstAccessor weight = grids_->weight->getConstAccessor();
  const float min_w = static_cast<float>(config_.min_weight);
  const double vs = config_.voxel_m;
  ScanPoints out;
  float v[8];
  for (auto it = grids_->weight->cbeginValueOn(); it; ++it) {
    if (!it.isVoxelValue() || *it < min_w) continue;
    const Coord c = it.getCoord();
    if (c.x() < cell_x_min || c.x() >= cell_x_max) continue;
    if (!loadCell(tsdf, weight, c, min_w, v) || !hasCrossing(v)) continue;
    Eigen::Vector3d x = meanCrossing(v);
    Eigen::Vector3d g;
    const double f = trilinear(v, x, &g);
    if (g.squaredNorm() > 1e-20) x = (x - f * g / g.squaredNorm()).cwiseMax(0.0).cwiseMin(1.0);  // one Newton step
    trilinear(v, x, &g);
    if (!(g.norm() > 1e-12)) continue;  // a flat field has no normal: not a surface
    const Eigen::Vector3d p = (Eigen::Vector3d(c.x(), c.y(), c.z()) + x) * vs;
    out.points.push_back(p.cast<float>());
    out.normals.push_back(g.normalized().cast<float>());  // increasing distance: the free side
  }
  return out;
}

namespace {
/// Drops pinched fans (dropPinchedFans) and the vertices no face uses any more.
void dropPinchedFansOf(TriangleMesh& mesh) {
  if (dropPinchedFans(mesh.faces, mesh.vertices.size()) == 0) return;
  TriangleMesh kept;
  std::vector<int> remap(mesh.vertices.size(), -1);
  for (const Eigen::Vector3i& f : mesh.faces) {
    Eigen::Vector3i g;
    for (int k = 0; k < 3; ++k) {
      if (remap[f[k]] < 0) {
        remap[f[k]] = static_cast<int>(kept.vertices.size());
        kept.vertices.push_back(mesh.vertices[f[k]]);
        kept.normals.push_back(mesh.normals[f[k]]);
      }
      g[k] = remap[f[k]];
    }
    kept.faces.push_back(g);
  }
  mesh = std::move(kept);
}
}  // namespace

TriangleMesh FusedMap::extractMesh() const {
  TriangleMesh mesh = extractSlabMesh(std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  // Where cells next to unseen ones were left out, two sheets can meet in one vertex: keep each
  // such vertex's largest fan (a manifold mesh for the checks and the Ball Pivoting tools).
  dropPinchedFansOf(mesh);
  return mesh;
}

TriangleMesh FusedMap::extractSlabMesh(int cell_x_min, int cell_x_max) const {
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  std::vector<openvdb::Vec4I> quads;
  openvdb::tools::volumeToMesh(*grids_->tsdf, points, triangles, quads, 0.0, 0.0);

  const ConstAccessor tsdf = grids_->tsdf->getConstAccessor();
  const ConstAccessor weight = grids_->weight->getConstAccessor();
  const float min_w = static_cast<float>(config_.min_weight);
  const double vs = config_.voxel_m;
  // Per vertex: its cell (volumeToMesh puts one vertex into each surface cell) must be observed.
  std::vector<int> index(points.size(), -1);
  std::vector<char> ok(points.size(), 0);
  std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f::Zero());
  std::vector<int> cell_x(points.size(), 0);
  float v[8];
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d u(points[i].x() / vs, points[i].y() / vs, points[i].z() / vs);
    const Coord c(static_cast<int>(std::floor(u.x())), static_cast<int>(std::floor(u.y())),
                  static_cast<int>(std::floor(u.z())));
    cell_x[i] = c.x();
    if (!loadCell(tsdf, weight, c, min_w, v)) continue;
    Eigen::Vector3d g;
    trilinear(v, (u - Eigen::Vector3d(c.x(), c.y(), c.z())).cwiseMax(0.0).cwiseMin(1.0), &g);
    if (g.norm() > 1e-12) normals[i] = g.normalized().cast<float>();
    ok[i] = 1;
  }
  TriangleMesh mesh;
  const auto use = [&](uint32_t i) {
    if (index[i] < 0) {
      index[i] = static_cast<int>(mesh.vertices.size());
      mesh.vertices.emplace_back(points[i].x(), points[i].y(), points[i].z());
      mesh.normals.push_back(normals[i]);
    }
    return index[i];
  };
  // volumeToMesh winds its polygons counter-clockwise seen from the positive (free) side, the
  // project's convention (checked by the sphere test: every face turned outwards).
  const auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    if (!ok[a] || !ok[b] || !ok[c]) return;
    mesh.faces.emplace_back(use(a), use(b), use(c));
  };
  // A polygon belongs to the slab of its cells' smallest x index (every polygon to one slab).
  const auto owned = [&](std::initializer_list<uint32_t> corners) {
    int lowest = std::numeric_limits<int>::max();
    for (const uint32_t k : corners) lowest = std::min(lowest, cell_x[k]);
    return lowest >= cell_x_min && lowest < cell_x_max;
  };
  for (const openvdb::Vec3I& t : triangles)
    if (owned({t[0], t[1], t[2]})) add(t[0], t[1], t[2]);
  for (const openvdb::Vec4I& q : quads) {
    if (!owned({q[0], q[1], q[2], q[3]})) continue;
    add(q[0], q[1], q[2]);
    add(q[0], q[2], q[3]);
  }
  return mesh;
}

float FusedMap::distanceAt(const Eigen::Vector3f& p) const {
  const Eigen::Vector3d u = p.cast<double>() / config_.voxel_m + Eigen::Vector3d::Constant(0.5);
  const Coord c(static_cast<int>(std::floor(u.x())), static_cast<int>(std::floor(u.y())),
                static_cast<int>(std::floor(u.z())));
  return grids_->tsdf->getConstAccessor().getValue(c);
}

float FusedMap::weightAt(const Eigen::Vector3f& p) const {
  const Eigen::Vector3d u = p.cast<double>() / config_.voxel_m + Eigen::Vector3d::Constant(0.5);
  const Coord c(static_cast<int>(std::floor(u.x())), static_cast<int>(std::floor(u.y())),
                static_cast<int>(std::floor(u.z())));
  return grids_->weight->getConstAccessor().getValue(c);
}

size_t FusedMap::activeVoxels() const { return static_cast<size_t>(grids_->weight->activeVoxelCount()); }

size_t FusedMap::observedVoxels() const {
  const float min_w = static_cast<float>(config_.min_weight);
  size_t n = 0;
  for (auto it = grids_->weight->cbeginValueOn(); it; ++it) {
    if (*it < min_w) continue;
    n += it.isVoxelValue() ? 1 : static_cast<size_t>(it.getVoxelCount());
  }
  return n;
}

size_t FusedMap::memoryBytes() const {
  return static_cast<size_t>(grids_->tsdf->memUsage() + grids_->weight->memUsage());
}

void FusedMap::save(const std::string& path) const {
  const std::string problem = outputFileProblem(path);
  if (!problem.empty()) throw IoError(path, "cannot write: " + problem);
  const std::string tmp = temporaryPathFor(path);
  try {
    openvdb::io::File file(tmp);
    openvdb::GridPtrVec grids{grids_->tsdf, grids_->weight};
    file.write(grids);
    file.close();
  } catch (const std::exception& e) {
    ::remove(tmp.c_str());
    throw IoError(path, std::string("cannot write the OpenVDB file: ") + e.what());
  }
  commitTemporaryFile(tmp, path);
}

size_t integrateMapDirectory(FusedMap& fused, const std::string& dir, std::vector<std::string>* skipped,
                             const std::vector<uint8_t>* only) {
  const auto t0 = std::chrono::steady_clock::now();
  const double seconds_before = fused.stats_.integrate_seconds;
  const std::unique_ptr<const MapDirectory> opened = openMapDirectory(dir, skipped);
  const MapDirectory& map = *opened;
  const size_t n = map.size();
  if (only && only->size() != n)
    throw std::invalid_argument("integrateMapDirectory: " + std::to_string(only->size()) + " scans chosen of " +
                                std::to_string(n));
  // Scans left out (`only`) are not read; the runs of the threads stay those of all n scans, so that a
  // voxel gets the same updates in the same order whichever scans are left out around it.
  const auto chosen = [&](size_t s) { return !only || (*only)[s]; };
  if (only && std::none_of(only->begin(), only->end(), [](uint8_t c) { return c != 0; })) return 0;
  const int threads = static_cast<int>(std::min<size_t>(std::max(1, fused.config().threads), n));
  // Thread t takes the scans [first(t), first(t + 1)): runs of consecutive scans.
  const auto first = [&](int t) { return n * static_cast<size_t>(t) / static_cast<size_t>(threads); };
  // A scan in the map frame with its sensor origin; false (and the problem in `problem`) when its file
  // cannot be read.
  const auto load = [&](size_t s, std::vector<Eigen::Vector3f>& points, Eigen::Vector3f& origin, std::string& problem) {
    const MapScanInfo& info = map.scans()[s];
    PointCloud scan;
    try {
      scan = map.loadScan(s);
    } catch (const std::exception& e) {
      if (!skipped) throw;  // strict: the file's own error
      problem = "scan " + std::to_string(info.index) + " skipped: " + e.what();
      return false;
    }
    const Eigen::Isometry3f T_map_base = info.map_pose.toIsometry3f();
    points.resize(scan.points.size());
    for (size_t i = 0; i < scan.points.size(); ++i) points[i] = T_map_base * scan.points[i];  // NaN stays NaN
    origin = T_map_base * info.sensor_origin.cast<float>();
    return true;
  };
  const auto inThreads = [&](const std::function<void(int)>& work) { runInThreads(threads, work); };

  // The near pass: each thread into grids of its own (the first into `fused`), merged afterwards.
  std::vector<std::unique_ptr<FusedMap>> parts;
  FusedMapConfig part_config = fused.config();
  for (int t = 1; t < threads; ++t) {
    parts.emplace_back(new FusedMap(part_config));
    parts.back()->bound_share_ = 1.0 / threads;
  }
  fused.bound_share_ = 1.0 / threads;
  std::vector<std::vector<std::string>> problems(threads);
  std::vector<size_t> loaded(threads, 0);
  try {
    inThreads([&](int t) {
      FusedMap& into = t == 0 ? fused : *parts[t - 1];
      std::vector<Eigen::Vector3f> points;
      Eigen::Vector3f origin;
      for (size_t s = first(t); s < first(t + 1); ++s) {
        if (!chosen(s)) continue;
        std::string problem;
        if (!load(s, points, origin, problem)) {
          problems[t].push_back(problem);
          continue;
        }
        into.integrate(points, origin);
        ++loaded[t];
      }
    });
  } catch (...) {
    fused.bound_share_ = 1.0;
    throw;
  }
  fused.bound_share_ = 1.0;
  for (const auto& part : parts) fused.merge(*part);
  parts.clear();
  size_t total = 0;
  for (int t = 0; t < threads; ++t) {
    total += loaded[t];
    if (skipped) skipped->insert(skipped->end(), problems[t].begin(), problems[t].end());
  }
  if (total == 0) throw IoError(dir, "none of its " + std::to_string(n) + " scan files could be read");

  if (fused.config().carve_far)  // every beam's far free space, now that every surface's voxels exist
    fused.carveFarAll(
        n,
        [&](size_t s, std::vector<Eigen::Vector3f>& points, Eigen::Vector3f& origin) {
          std::string problem;
          // (a scan that cannot be read was named in the near pass)
          return chosen(s) && load(s, points, origin, problem);
        },
        threads);
  fused.stats_.integrate_seconds = seconds_before + elapsed(t0);
  return total;
}

bool isFusedMeshMethod(const std::string& method) { return method == "marching_cubes" || method == "fused_bpa"; }

namespace {

/// The x ranges [m] of a map directory's scans at their map poses: per scan, of its readings and its
/// sensor origin (what its beams can reach; NaN for a scan that cannot be read: integrateMapDirectory
/// names it), and of all readings.
struct XExtents {
  std::vector<std::pair<double, double>> scans;
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
};
XExtents mapXExtents(const std::string& dir) {
  std::vector<std::string> named_by_the_passes;
  const std::unique_ptr<const MapDirectory> opened = openMapDirectory(dir, &named_by_the_passes);
  XExtents out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.scans.assign(opened->size(), {nan, nan});
  for (size_t s = 0; s < opened->size(); ++s) {
    PointCloud scan;
    try {
      scan = opened->loadScan(s);
    } catch (const std::exception&) {
      continue;
    }
    const MapScanInfo& info = opened->scans()[s];
    const Eigen::Isometry3f T = info.map_pose.toIsometry3f();
    const double origin = (T * info.sensor_origin.cast<float>()).x();
    double lo = origin, hi = origin;
    for (const Eigen::Vector3f& p : scan.points) {
      if (!p.allFinite()) continue;
      const double x = (T * p).x();
      lo = std::min(lo, x);
      hi = std::max(hi, x);
      out.lo = std::min(out.lo, x);
      out.hi = std::max(out.hi, x);
    }
    out.scans[s] = {lo, hi};
  }
  return out;
}

}  // namespace

FusedMesh meshFusedMapInSlabs(const std::string& dir, const FusedMapConfig& config, const std::string& method,
                              const MesherConfig& bpa, std::vector<std::string>* skipped, double min_slab_m,
                              const DecimateConfig* decimate_slabs) {
  if (!isFusedMeshMethod(method))
    throw std::invalid_argument("mesh method '" + method + "' is not one of marching_cubes, fused_bpa");
  const double vs = config.voxel_m;
  const XExtents x = mapXExtents(dir);
  if (!(x.lo <= x.hi)) throw IoError(dir, "no readable point in its scans");
  const int first = static_cast<int>(std::floor(x.lo / vs)) - 2, last = static_cast<int>(std::floor(x.hi / vs)) + 2;
  // How far beyond its beams' x range a scan can update a voxel: the band behind the hit, the lateral
  // splat, half a voxel, and a voxel to spare.
  const double reach = config.truncation_m + (config.splat + 2) * vs;
  size_t readable = 0;
  for (const auto& e : x.scans) readable += std::isfinite(e.first) ? 1 : 0;
  const int min_cells = std::max(8, static_cast<int>(std::ceil(min_slab_m / vs)));
  FusedMesh out;
  out.slabs = 0;
  ScanPoints surface;
  // Vertices within a cell of a slab border, by their exact coordinates: two slabs compute the
  // same vertex bit for bit (the same voxels, updated by the same readings in the same order).
  std::unordered_map<std::string, int> border_vertices;
  std::vector<int> borders;
  bool first_pass = true;
  const std::function<void(int, int)> build = [&](int a, int b) {  // cells [a, b)
    FusedMapConfig slab = config;
    slab.clip_x_min_voxel = a - 1;
    slab.clip_x_max_voxel = b + 2;
    auto held = std::make_unique<FusedMap>(slab);
    FusedMap& fused = *held;
    std::vector<std::string> later;  // every pass names the same skipped scans: the first whole one says it
    const size_t named = skipped ? skipped->size() : 0;
    // Only the scans whose beams reach the slab (and those that cannot be read, to be named).
    const double x_lo = (slab.clip_x_min_voxel - 0.5) * vs, x_hi = (slab.clip_x_max_voxel + 0.5) * vs;
    std::vector<uint8_t> only(x.scans.size());
    for (size_t s = 0; s < only.size(); ++s)
      only[s] =
          !std::isfinite(x.scans[s].first) || (x.scans[s].second + reach >= x_lo && x.scans[s].first - reach <= x_hi);
    try {
      const size_t read = integrateMapDirectory(fused, dir, first_pass ? skipped : (skipped ? &later : nullptr), &only);
      out.scans_read += read;
    } catch (const GridBoundError& e) {
      if (skipped) skipped->resize(named);  // a pass that stopped at the bound: the next one names them
      if (b - a < 2 * min_cells)
        throw GridBoundError(std::string(e.what()) + " (in a slab of " + std::to_string((b - a) * vs) + " m along x)");
      held.reset();    // the halves must not share the bound with the grids that passed it
      malloc_trim(0);  // nor build their grids around the freed ones' fragments
      build(a, a + (b - a) / 2);
      build(a + (b - a) / 2, b);
      return;
    }
    first_pass = false;
    out.scans = readable;
    ++out.slabs;
    out.integrate_s += fused.stats().integrate_seconds;
    out.voxels += fused.activeVoxels();
    out.memory_bytes = std::max(out.memory_bytes, fused.memoryBytes());
    const auto start = std::chrono::steady_clock::now();
    if (method != "marching_cubes") {  // Marching Cubes shows its vertices (one per surface cell)
      const ScanPoints part = fused.surfacePoints(a, b);
      surface.points.insert(surface.points.end(), part.points.begin(), part.points.end());
      surface.normals.insert(surface.normals.end(), part.normals.begin(), part.normals.end());
    }
    if (method == "marching_cubes") {
      TriangleMesh m = fused.extractSlabMesh(a, b);
      if (decimate_slabs && decimate_slabs->max_error_m > 0.0) {
        fused = FusedMap(slab);  // the grids are done with: not held while decimating
        // The vertices within a cell of a border stay: the vertices the neighbour shares keep their
        // neighbours among themselves, so no collapse joins two of them by an edge the neighbour has too.
        std::vector<char> pinned(m.vertices.size());
        for (size_t i = 0; i < m.vertices.size(); ++i) {
          const int cell = static_cast<int>(std::floor(m.vertices[i].x() / vs));
          pinned[i] = cell <= a || cell >= b - 1;
        }
        out.decimated.add(decimateMesh(m, *decimate_slabs, pinned));
      }
      std::vector<int> index(m.vertices.size());
      for (size_t i = 0; i < m.vertices.size(); ++i) {
        const int cell = static_cast<int>(std::floor(m.vertices[i].x() / vs));
        const bool near_border = cell <= a || cell >= b - 1;
        std::string key;
        if (near_border) {
          key.assign(reinterpret_cast<const char*>(m.vertices[i].data()), 3 * sizeof(float));
          const auto found = border_vertices.find(key);
          if (found != border_vertices.end()) {
            index[i] = found->second;
            continue;
          }
        }
        index[i] = static_cast<int>(out.mesh.vertices.size());
        out.mesh.vertices.push_back(m.vertices[i]);
        out.mesh.normals.push_back(m.normals[i]);
        if (near_border) border_vertices.emplace(key, index[i]);
      }
      for (const Eigen::Vector3i& f : m.faces) out.mesh.faces.emplace_back(index[f[0]], index[f[1]], index[f[2]]);
    }
    out.mesh_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const int mid = first + (last - first) / 2;
  build(first, mid);
  build(mid, last);
  const auto start = std::chrono::steady_clock::now();
  if (method == "marching_cubes") {
    dropPinchedFansOf(out.mesh);
    surface.points = out.mesh.vertices;
  } else {
    out.surface_points = surface.size();
    if (surface.size() > 0) out.mesh = buildMesh(surface, bpa).mesh;
  }
  out.mesh_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.surface = std::move(surface.points);
  if (out.mesh.faces.empty())
    throw std::runtime_error("nothing to mesh: the fused map of " + dir + " holds no observed surface");
  return out;
}

FusedMesh meshFusedMapDirectory(const std::string& dir, const FusedMapConfig& config, const std::string& method,
                                const MesherConfig& bpa, std::vector<std::string>* skipped,
                                const std::string& save_path, double min_slab_m, const DecimateConfig* decimate_slabs) {
  if (!isFusedMeshMethod(method))
    throw std::invalid_argument("mesh method '" + method + "' is not one of marching_cubes, fused_bpa");
  FusedMesh out;
  const size_t skipped_before = skipped ? skipped->size() : 0;
  try {
    FusedMap fused(config);
    out.scans = integrateMapDirectory(fused, dir, skipped);
    out.scans_read = out.scans;
    out.integrate_s = fused.stats().integrate_seconds;
    out.voxels = fused.activeVoxels();
    out.memory_bytes = fused.memoryBytes();
    const auto start = std::chrono::steady_clock::now();
    if (method == "marching_cubes") {
      out.mesh = fused.extractMesh();
      out.surface = out.mesh.vertices;  // one per surface cell, as surfacePoints()
    } else {
      ScanPoints surface = fused.surfacePoints();
      out.surface_points = surface.size();
      if (surface.size() > 0) out.mesh = buildMesh(surface, bpa).mesh;
      out.surface = std::move(surface.points);
    }
    out.mesh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!save_path.empty()) try {
        fused.save(save_path);
      } catch (const IoError& e) {
        out.save_problem = e.what();
      }
  } catch (const GridBoundError&) {
    // Too large as a whole: in slabs (the scans' problems are named again by the slabs' pass).
    if (skipped) skipped->resize(skipped_before);
    malloc_trim(0);  // the whole map's grids are gone: the slabs' grids start from a trimmed heap
    out = meshFusedMapInSlabs(dir, config, method, bpa, skipped, min_slab_m, decimate_slabs);
  }
  if (out.mesh.faces.empty())
    throw std::runtime_error("nothing to mesh: the fused map of " + dir + " holds no observed surface");
  return out;
}

}  // namespace mesher
}  // namespace scanstop
