#include "scanstop_slam/icp.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace slam {

VoxelMap::VoxelMap(double voxel_m, int max_points_per_voxel, double min_spacing_m)
    : voxel_(voxel_m),
      max_per_voxel_(max_points_per_voxel),
      min_spacing2_(static_cast<float>(min_spacing_m * min_spacing_m)) {
  requirePositive("voxel", voxel_m, "m");
  requireInRange("map_spacing", min_spacing_m, 0.0, voxel_m, "m");
  if (max_points_per_voxel < 1) throw ConfigError("max_points_per_voxel must be >= 1");
}

namespace {
/// splitmix64's finalizer: spreads neighbouring voxel keys over the whole table.
/// 4 floats as one value: GCC/Clang vector extension, one SSE2 register (x86-64 baseline; 8-wide
/// values without AVX make GCC lower the lane-wise minimum to scalar code).
typedef float Quad __attribute__((vector_size(sizeof(float) * 4)));
#define SCANSTOP_SPLAT4(v) Quad{v, v, v, v}
typedef int32_t QuadMask __attribute__((vector_size(sizeof(int32_t) * 4)));  ///< lane-wise comparison

inline uint64_t mixKey(uint64_t k) {
  k ^= k >> 30;
  k *= 0xbf58476d1ce4e5b9ULL;
  k ^= k >> 27;
  k *= 0x94d049bb133111ebULL;
  return k ^ (k >> 31);
}
}  // namespace

int32_t VoxelMap::findBrick(Key k) const {
  if (slot_keys_.empty()) return -1;
  for (size_t i = mixKey(static_cast<uint64_t>(k)) & slot_mask_;; i = (i + 1) & slot_mask_) {
    const int32_t c = slot_bricks_[i];
    if (c < 0) return -1;
    if (slot_keys_[i] == k) return c;
  }
}

void VoxelMap::growTable() {
  const size_t capacity = slot_keys_.empty() ? 1024 : slot_keys_.size() * 2;
  slot_keys_.assign(capacity, 0);
  slot_bricks_.assign(capacity, -1);
  slot_mask_ = capacity - 1;
  for (size_t b = 0; b < bricks_.size(); ++b) {
    size_t i = mixKey(static_cast<uint64_t>(bricks_[b].key)) & slot_mask_;
    while (slot_bricks_[i] >= 0) i = (i + 1) & slot_mask_;
    slot_keys_[i] = bricks_[b].key;
    slot_bricks_[i] = static_cast<int32_t>(b);
  }
}

int32_t VoxelMap::findCell(int x, int y, int z) const {
  const int32_t b = findBrick(key(x >> 2, y >> 2, z >> 2));
  if (b < 0) return -1;
  const Brick& brick = bricks_[b];
  const int bit = brickBit(x, y, z);
  return brick.occupied >> bit & 1 ? brick.cells[bit] : -1;
}

int32_t VoxelMap::findOrAddCell(int x, int y, int z) {
  const Key k = key(x >> 2, y >> 2, z >> 2);  // arithmetic shift: floor division by 4
  if (2 * (bricks_.size() + 1) > slot_keys_.size()) growTable();
  size_t i = mixKey(static_cast<uint64_t>(k)) & slot_mask_;
  for (; slot_bricks_[i] >= 0; i = (i + 1) & slot_mask_)
    if (slot_keys_[i] == k) break;
  if (slot_bricks_[i] < 0) {
    if (bricks_.size() >= static_cast<size_t>(std::numeric_limits<int32_t>::max()))
      throw std::length_error("VoxelMap: more than 2^31 bricks");
    slot_keys_[i] = k;
    slot_bricks_[i] = static_cast<int32_t>(bricks_.size());
    bricks_.emplace_back();
    bricks_.back().key = k;
  }
  Brick& brick = bricks_[slot_bricks_[i]];
  const int bit = brickBit(x, y, z);
  if (brick.occupied >> bit & 1) return brick.cells[bit];
  if (cells_.size() >= static_cast<size_t>(std::numeric_limits<int32_t>::max()))
    throw std::length_error("VoxelMap: more than 2^31 voxels");
  brick.occupied |= uint64_t{1} << bit;
  brick.cells[bit] = static_cast<int32_t>(cells_.size());
  cells_.emplace_back();
  cells_.back().key = key(x, y, z);
  return brick.cells[bit];
}

VoxelMap::Key VoxelMap::key(int x, int y, int z) {
  // 21 bits per axis (+-1e6 voxels): +-100 km at 10 cm.
  const auto enc = [](int v) { return static_cast<int64_t>(v + (1 << 20)) & ((1 << 21) - 1); };
  return (enc(x) << 42) | (enc(y) << 21) | enc(z);
}

void VoxelMap::decode(Key k, int& x, int& y, int& z) {
  const auto dec = [](int64_t bits) { return static_cast<int>(bits & ((1 << 21) - 1)) - (1 << 20); };
  x = dec(k >> 42);
  y = dec(k >> 21);
  z = dec(k);
}

void VoxelMap::Cell::push(const Eigen::Vector3f& p, const Eigen::Vector3f& view) {
  const size_t lane = count % kLanes;
  if (lane == 0) blocks.resize(blocks.size() + 3 * kLanes, std::numeric_limits<float>::infinity());
  float* b = &blocks[blocks.size() - 3 * kLanes + lane];
  b[0] = p.x();
  b[kLanes] = p.y();
  b[2 * kLanes] = p.z();
  for (int a = 0; a < 3; ++a) views.push_back(static_cast<int8_t>(std::lround(std::clamp(view[a], -1.0f, 1.0f) * 127.0f)));
  ++count;
}

void VoxelMap::classify(Cell& cell) {
  cell.horizontal = false;
  if (cell.count < 5) return;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < cell.count; ++i) mean += cell.point(i).cast<double>();
  mean /= static_cast<double>(cell.count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < cell.count; ++i) {
    const Eigen::Vector3d d = cell.point(i).cast<double>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  // Planar (smallest spread well below the others) with a normal near z.
  const bool planar = eig.eigenvalues()(0) < 0.05 * eig.eigenvalues()(1);
  cell.horizontal = planar && std::abs(eig.eigenvectors().col(0).z()) > std::cos(20.0 * M_PI / 180.0);
}

void VoxelMap::estimateNormal(Cell& cell) const {
  // The voxel's points and those of its 6 face neighbours: a voxel boundary may cut a thin slice off
  // a noisy wall (3 cm of a 10 cm voxel with 1 cm noise is no plane by itself), and the neighbour
  // across it holds the rest. Both faces of a thin wall give the same normal; the points' views
  // tell the faces apart.
  int x, y, z;
  decode(cell.key, x, y, z);
  static const int kOffsets[7][3] = {{0, 0, 0}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum2 = Eigen::Matrix3d::Zero();
  size_t n = 0;
  for (const auto& o : kOffsets) {
    const int32_t c = findCell(x + o[0], y + o[1], z + o[2]);
    if (c < 0) continue;
    const Cell& other = cells_[c];
    for (size_t i = 0; i < other.count; ++i) {
      const Eigen::Vector3d p = other.point(i).cast<double>();
      sum += p;
      sum2 += p * p.transpose();
      ++n;
    }
  }
  cell.planar = false;
  if (n < 8) return;
  const Eigen::Vector3d mean = sum / static_cast<double>(n);
  const Eigen::Matrix3d cov = sum2 / static_cast<double>(n) - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  cell.normal = eig.eigenvectors().col(0).cast<float>();
  cell.planar = eig.eigenvalues()(0) < 0.3 * eig.eigenvalues()(1);
}

void VoxelMap::add(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f* sensor_origin) {
  std::vector<int32_t> touched;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const int x = static_cast<int>(std::floor(p.x() / voxel_));
    const int y = static_cast<int>(std::floor(p.y() / voxel_));
    const int z = static_cast<int>(std::floor(p.z() / voxel_));
    const int32_t c = findOrAddCell(x, y, z);
    Cell& cell = cells_[c];
    if (cell.count >= static_cast<uint32_t>(max_per_voxel_)) continue;
    if (min_spacing2_ > 0.0f) {
      bool crowded = false;
      for (size_t i = 0; i < cell.count; ++i)
        if ((cell.point(i) - p).squaredNorm() < min_spacing2_) {
          crowded = true;
          break;
        }
      if (crowded) continue;
    }
    Eigen::Vector3f view = Eigen::Vector3f::Zero();
    if (sensor_origin) {
      const Eigen::Vector3f d = *sensor_origin - p;
      if (d.squaredNorm() > 0.0f) view = d.normalized();
    }
    cell.push(p, view);
    touched.push_back(c);
    ++size_;
  }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  // Only the touched voxels get a new normal, from the points their neighbours hold now; a
  // neighbour's normal is not refreshed when this scan adds to it. Refreshing them was tried: at
  // 400 planes a little better, at 50 planes worse (the chaos rostest's run, seed 7: scan 4 off by
  // 21.9 instead of 8.3 cm), as more sparse voxels got a normal that rejected good pairs.
  for (const int32_t c : touched) {
    classify(cells_[c]);
    estimateNormal(cells_[c]);
  }
}

bool VoxelMap::nearest(const Eigen::Vector3f& q, double radius_m, Eigen::Vector3f& out, float& dist2,
                       bool* horizontal, Surface* surface) const {
  const float inv = static_cast<float>(1.0 / voxel_);
  const float vs = static_cast<float>(voxel_);
  const int x = static_cast<int>(std::floor(q.x() * inv));
  const int y = static_cast<int>(std::floor(q.y() * inv));
  const int z = static_cast<int>(std::floor(q.z() * inv));
  // Offsets of q inside its voxel: a neighbour voxel is searched only when its box is closer to q
  // than the best point so far (the own voxel first, so on surfaces most neighbours are skipped).
  const float lo[3] = {q.x() - x * vs, q.y() - y * vs, q.z() - z * vs};
  const float hi[3] = {vs - lo[0], vs - lo[1], vs - lo[2]};
  float best = static_cast<float>(radius_m * radius_m);
  bool found = false;
  static_assert(kLanes % 4 == 0, "a block row is whole SSE registers");
  const Quad qx = SCANSTOP_SPLAT4(q.x()), qy = SCANSTOP_SPLAT4(q.y()), qz = SCANSTOP_SPLAT4(q.z());
  const Brick* brick = nullptr;  // the brick of the last voxel looked up (nullptr: none there)
  Key brick_key = -1;            // its key (-1: no lookup yet; keys are >= 0)
  const auto scan = [&](int dx, int dy, int dz, float box2) {
    if (box2 >= best) return;
    const int vx = x + dx, vy = y + dy, vz = z + dz;
    const Key bk = key(vx >> 2, vy >> 2, vz >> 2);
    if (bk != brick_key) {
      brick_key = bk;
      const int32_t b = findBrick(bk);
      brick = b < 0 ? nullptr : &bricks_[b];
    }
    if (!brick) return;
    const int bit = brickBit(vx, vy, vz);
    if (!(brick->occupied >> bit & 1)) return;
    const int32_t c = brick->cells[bit];
    const Cell& cell = cells_[c];
    const float* blocks = cell.blocks.data();
    const size_t n_blocks = cell.blocks.size() / (3 * kLanes);
    // Chunks of blocks: every squared distance of a chunk into dist (SIMD, the same float operations
    // in the same order as Eigen's (p - q).squaredNorm(): dx*dx + (dy*dy + dz*dz)) and their lane-wise
    // minimum with best; then the first point of the chunk at that minimum, if it is below best.
    // That is the point the plain loop "if (d2 < best) take it" picks: exact, ties to the first.
    constexpr size_t kChunk = 32;  // blocks
    constexpr int kQuads = kLanes / 4;
    Quad dist[kChunk * kQuads];
    for (size_t b0 = 0; b0 < n_blocks; b0 += kChunk) {
      const size_t nb = std::min(kChunk, n_blocks - b0);
      Quad m[kQuads];
      for (int h = 0; h < kQuads; ++h) m[h] = SCANSTOP_SPLAT4(best);
      for (size_t b = 0; b < nb; ++b) {
        const float* p = blocks + (b0 + b) * 3 * kLanes;
        for (int h = 0; h < kQuads; ++h) {  // independent halves: two minimum chains in flight
          Quad px, py, pz;
          std::memcpy(&px, p + 4 * h, sizeof(Quad));
          std::memcpy(&py, p + kLanes + 4 * h, sizeof(Quad));
          std::memcpy(&pz, p + 2 * kLanes + 4 * h, sizeof(Quad));
          const Quad ex = px - qx, ey = py - qy, ez = pz - qz;
          const Quad d2 = ex * ex + (ey * ey + ez * ez);
          dist[b * kQuads + h] = d2;
          m[h] = d2 < m[h] ? d2 : m[h];
        }
      }
      float chunk_min = best;
      for (int h = 0; h < kQuads; ++h)
        for (int l = 0; l < 4; ++l) chunk_min = m[h][l] < chunk_min ? m[h][l] : chunk_min;
      if (!(chunk_min < best)) continue;
      // The first lane at the minimum (padding lanes are +inf, never the minimum): a whole
      // register compared at a time, then its lanes.
      const Quad at = SCANSTOP_SPLAT4(chunk_min);
      size_t j = 0;
      for (;; ++j) {
        const QuadMask eq = dist[j] == at;
        uint64_t bits[2];
        std::memcpy(bits, &eq, sizeof(bits));
        if (bits[0] | bits[1]) break;
      }
      size_t i = 4 * j;
      while (dist[j][i % 4] != chunk_min) ++i;
      best = chunk_min;
      out = cell.point(b0 * kLanes + i);
      found = true;
      if (horizontal) *horizontal = cell.horizontal;
      if (surface) {
        surface->planar = cell.planar;
        surface->normal = cell.normal;
        surface->view = cell.view(b0 * kLanes + i);
      }
    }
  };
  scan(0, 0, 0, 0.0f);
  // Shells of neighbour voxels out to the radius (one shell when radius <= voxel), nearest shell
  // first: every voxel of shell k is at least (k - 1) voxels plus q's smallest offset to a face of
  // its own voxel away, so once the best point is closer than that no farther shell can hold a
  // closer one (exact, and a small voxel with a large radius costs what the points near q cost).
  const int rings = std::max(1, static_cast<int>(std::ceil(radius_m / voxel_ - 1e-9)));
  const float face = std::min({lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]});
  // Squared gaps between q and the voxel d along each axis (d = -rings..rings), computed once per
  // query instead of per voxel; a voxel's box distance is (gx^2 + gy^2) + gz^2 as a sum in axis
  // order, so a row of voxels whose partial sum is already at best is skipped whole.
  constexpr int kSmallWidth = 17;  // up to 8 rings on the stack
  float gap2_small[3 * kSmallWidth];
  std::vector<float> gap2_large;
  const int width = 2 * rings + 1;
  float* gap2 = gap2_small;
  if (width > kSmallWidth) {
    gap2_large.resize(3 * width);
    gap2 = gap2_large.data();
  }
  for (int a = 0; a < 3; ++a)
    for (int d = -rings; d <= rings; ++d) {
      const float g = d < 0 ? lo[a] + (-d - 1) * vs : (d > 0 ? hi[a] + (d - 1) * vs : 0.0f);
      gap2[a * width + d + rings] = g * g;
    }
  const float* gx2 = gap2 + rings;
  const float* gy2 = gap2 + width + rings;
  const float* gz2 = gap2 + 2 * width + rings;
  for (int k = 1; k <= rings; ++k) {
    const float shell = (k - 1) * vs + face;
    if (shell * shell >= best) break;
    for (int dx = -k; dx <= k; ++dx) {
      if (gx2[dx] >= best) continue;
      for (int dy = -k; dy <= k; ++dy) {
        const float bxy = gx2[dx] + gy2[dy];
        if (bxy >= best) continue;
        const bool side = dx == -k || dx == k || dy == -k || dy == k;
        for (int dz = -k; dz <= k; dz += side ? 1 : 2 * k) scan(dx, dy, dz, bxy + gz2[dz]);  // the shell's surface only
      }
    }
  }
  dist2 = best;
  return found;
}

std::vector<Eigen::Vector3f> VoxelMap::points() const {
  std::vector<Eigen::Vector3f> out;
  out.reserve(size_);
  for (const auto& cell : cells_)
    for (size_t i = 0; i < cell.count; ++i) out.push_back(cell.point(i));
  return out;
}

void IcpConfig::validate() const {
  requireInRange("c_max", c_max_m, 0.001, 5.0, "m");
  requireInRange("t_c", t_c_m, 1e-9, 1.0, "m");
  requireInRange("r_c", r_c_rad, 1e-9, 1.0, "rad");
  requireInRange("max_iterations", max_iterations, 1, 10000);
  requireInRange("min_correspondences", min_correspondences, 3, 1e9);
  requireInRange("min_overlap", min_overlap, 0.0, 1.0);
  requirePositive("max_correction", max_correction_m, "m");
  requirePositive("max_correction_angle", max_correction_rad, "rad");
}

std::vector<Eigen::Vector3f> voxelDownsample(const std::vector<Eigen::Vector3f>& points, double voxel_m) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(points.size());
  if (voxel_m <= 0.0) {
    for (const auto& p : points)
      if (p.allFinite()) out.push_back(p);
    return out;
  }
  std::unordered_set<int64_t> seen;
  seen.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const auto enc = [voxel_m](float v) {
      return static_cast<int64_t>(std::floor(v / voxel_m) + (1 << 20)) & ((1 << 21) - 1);
    };
    const int64_t k = (enc(p.x()) << 42) | (enc(p.y()) << 21) | enc(p.z());
    if (seen.insert(k).second) out.push_back(p);
  }
  return out;
}

namespace {

/// Pose parameters: translation and rotation vector (rotation scaled by 1 m, so that both parts
/// weigh alike for a scene of metres).
Eigen::Matrix<double, 6, 1> params(const Eigen::Isometry3d& T) {
  Eigen::Matrix<double, 6, 1> p;
  const Eigen::AngleAxisd aa(T.linear());
  p << T.translation(), aa.axis() * aa.angle();
  return p;
}

Eigen::Isometry3d fromParams(const Eigen::Matrix<double, 6, 1>& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double angle = p.tail<3>().norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, p.tail<3>() / angle).toRotationMatrix();
  T.translation() = p.head<3>();
  return T;
}

}  // namespace

IcpResult icp(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source, const Eigen::Isometry3d& T_init,
              const IcpConfig& config, const Eigen::Vector3f* source_origin) {
  IcpResult result;
  Eigen::Isometry3d T = T_init;
  const long n = static_cast<long>(source.size());
  std::vector<Eigen::Vector3f> matched(source.size());
  std::vector<uint8_t> has(source.size(), 0);
  std::vector<float> dist2(config.unique_matches ? source.size() : 0);  // of each pair (unique_matches)
  std::vector<uint32_t> order;                                          // pairs sorted by map point
  const double c_max = config.c_max_m;
  // Exact shortcuts of the correspondence search, from what the last search of each point found.
  // A hit (its nearest map point m within c_max): m is a map point, so the nearest one now is no
  // farther than |q - m|, and that radius (padded against rounding) replaces c_max. A miss is
  // searched out to c_max + miss_margin; the distance of the nearest point found beyond c_max
  // (or that radius when there is none) is a lower bound at the searched position (anchor), and
  // while the point has moved less than that bound minus c_max from there it still has no match
  // within c_max and is not searched at all. Either way the result is the nearest map point within
  // c_max, as the full search finds it (poses identical up to exact distance ties).
  const bool reuse = config.reuse_search_bounds;
  const float c_max_f = static_cast<float>(c_max);
  const float c_max2_f = static_cast<float>(c_max * c_max);  // nearest()'s own bound for radius c_max
  const double miss_margin = 0.5 * c_max;
  std::vector<uint8_t> hit(source.size(), 0);     // last search: a map point within c_max (matched[i])
  std::vector<uint8_t> bounded(source.size(), 0); // last search: a miss with a lower bound
  std::vector<Eigen::Vector3f> anchor(reuse ? source.size() : 0);
  std::vector<float> lower(reuse ? source.size() : 0);  // nearest map point distance at anchor >= this [m]
  // The nearest map point within c_max of q (point i transformed); its squared distance in d2.
  const auto correspond = [&](long i, const Eigen::Vector3f& q, float& d2, bool& horizontal, Surface* surface) -> bool {
    if (!reuse) return target.nearest(q, c_max, matched[i], d2, &horizontal, surface);
    // Rounding allowance of the float distances and of nearest()'s voxel boxes [m].
    const float eps = 1e-4f + 1e-6f * q.cwiseAbs().maxCoeff();
    if (hit[i]) {
      const float d_last = (q - matched[i]).norm();
      // matched[i] lies within the radius, so this finds a point (the nearest one).
      if (d_last < c_max_f &&
          target.nearest(q, std::min(c_max, static_cast<double>(d_last + eps)), matched[i], d2, &horizontal, surface))
        return true;
    } else if (bounded[i] && lower[i] - (q - anchor[i]).norm() >= c_max_f + eps) {
      return false;
    }
    const double radius = c_max + miss_margin;
    Eigen::Vector3f m;
    const bool found = target.nearest(q, radius, m, d2, &horizontal, surface);
    if (found && d2 < c_max2_f) {
      matched[i] = m;
      hit[i] = 1;
      bounded[i] = 0;
      return true;
    }
    hit[i] = 0;
    bounded[i] = 1;
    anchor[i] = q;
    lower[i] = found ? std::sqrt(d2) : static_cast<float>(radius);
    return false;
  };
  // Same side (IcpConfig::same_side): where the map point's voxel is one plane and both points'
  // viewing directions are known and clear of it (more than ~6 deg), they must lie on the same side.
  const bool side_test = config.same_side && source_origin != nullptr;
  const auto sameSide = [&](const Eigen::Vector3f& q, const Eigen::Vector3f& origin, const Surface& s) {
    if (!s.planar) return true;
    const float map_side = s.normal.dot(s.view);
    const Eigen::Vector3f to_sensor = origin - q;
    const float n = to_sensor.norm();
    if (!(n > 0.0f)) return true;
    const float source_side = s.normal.dot(to_sensor) / n;
    constexpr float kClear = 0.1f;
    return !((map_side > kClear && source_side < -kClear) || (map_side < -kClear && source_side > kClear));
  };
  // The nearest map point within c_max that may pair with point i (at q; origin: the source's
  // sensor in the map frame).
  const auto pair = [&](long i, const Eigen::Vector3f& q, const Eigen::Vector3f& origin, float& d2,
                        bool& horizontal) -> bool {
    Surface s;
    if (!correspond(i, q, d2, horizontal, side_test ? &s : nullptr)) return false;
    return !side_test || sameSide(q, origin, s);
  };
  Eigen::Matrix<double, 6, 1> last_step = Eigen::Matrix<double, 6, 1>::Zero();
  const bool skip_horizontal = !config.six_dof && config.ignore_horizontal;
  Eigen::Matrix<double, 6, 1> last_params = params(T);
  for (int it = 1; it <= config.max_iterations; ++it) {
    result.iterations = it;
    const Eigen::Isometry3f Tf = T.cast<float>();
    const Eigen::Vector3f origin = side_test ? Eigen::Vector3f(Tf * *source_origin) : Eigen::Vector3f::Zero();
    // Correspondences (parallel): nearest map point within c_max of each transformed source point.
#pragma omp parallel for schedule(dynamic, 2048)
    for (long i = 0; i < n; ++i) {
      float d2;
      bool horizontal = false;
      has[i] = pair(i, Tf * source[i], origin, d2, horizontal) && !(skip_horizontal && horizontal) ? 1 : 0;
      if (config.unique_matches) dist2[i] = d2;
    }
    if (config.unique_matches) {
      // Of the source points paired with one map point (equal coordinates: the same stored point)
      // only the nearest keeps it (ties: the lower index, so the result does not depend on threads).
      order.clear();
      for (long i = 0; i < n; ++i)
        if (has[i]) order.push_back(static_cast<uint32_t>(i));
      std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const Eigen::Vector3f& p = matched[a];
        const Eigen::Vector3f& q = matched[b];
        if (p.x() != q.x()) return p.x() < q.x();
        if (p.y() != q.y()) return p.y() < q.y();
        if (p.z() != q.z()) return p.z() < q.z();
        return dist2[a] != dist2[b] ? dist2[a] < dist2[b] : a < b;
      });
      for (size_t k = 1; k < order.size(); ++k)
        if (matched[order[k]] == matched[order[k - 1]]) has[order[k]] = 0;
    }
    // Centroids and correlation (in double, relative to the current pose).
    // (The transformed source points are recomputed in double: float rounding would keep the
    // per-iteration change from ever falling below tight t_c / r_c.)
    Eigen::Vector3d cd = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
    size_t count = 0;
    for (long i = 0; i < n; ++i) {
      if (!has[i]) continue;
      cd += T * source[i].cast<double>();
      cm += matched[i].cast<double>();
      ++count;
    }
    result.correspondences = count;
    result.overlap = n > 0 ? static_cast<double>(count) / n : 0.0;
    if (count < static_cast<size_t>(config.min_correspondences)) {
      result.failure = "too few correspondences (" + std::to_string(count) + " < " +
                       std::to_string(config.min_correspondences) + ") within c_max = " + std::to_string(c_max) + " m";
      result.T_target_source = T_init;
      return result;
    }
    cd /= count;
    cm /= count;
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    for (long i = 0; i < n; ++i) {
      if (!has[i]) continue;
      H += (T * source[i].cast<double>() - cd) * (matched[i].cast<double>() - cm).transpose();
    }
    // Rotation from the SVD of the correlation matrix (Algorithm 4, lines 9-11): R = V U^T.
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    if (config.six_dof) {
      Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
      D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
      R = svd.matrixV() * D * svd.matrixU().transpose();
    } else {
      const Eigen::Matrix2d H2 = H.topLeftCorner<2, 2>();
      Eigen::JacobiSVD<Eigen::Matrix2d> svd(H2, Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix2d D = Eigen::Matrix2d::Identity();
      D(1, 1) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
      R.topLeftCorner<2, 2>() = svd.matrixV() * D * svd.matrixU().transpose();
    }
    Eigen::Vector3d t = cm - R * cd;
    if (!config.six_dof) t.z() = 0.0;
    Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
    delta.linear() = R;
    delta.translation() = t;
    T = delta * T;
    const double dt = t.norm();
    const double dr = Eigen::AngleAxisd(R).angle();
    // Besl and McKay's accelerated ICP (1992, section IV.C), linear form: point-to-point ICP
    // creeps towards the optimum in ever smaller steps along a nearly constant direction, so a
    // small step alone does not mean it has arrived (the thesis' criterion stops tenths of a
    // degree short). When two successive steps point the same way (within 10 deg) and shrink by
    // the ratio rho, the rest of the geometric series, step * rho / (1 - rho) (at most 25 steps),
    // is taken at once, and convergence is declared only when that rest is below t_c and r_c too.
    const Eigen::Matrix<double, 6, 1> p = params(T);
    const Eigen::Matrix<double, 6, 1> step = p - last_params;
    last_params = p;
    if (config.accelerate && last_step.norm() > 0.0 && step.norm() > 0.0 && p.tail<3>().norm() < 3.0) {
      const double cos_angle = step.dot(last_step) / (step.norm() * last_step.norm());
      const double rho = step.norm() / last_step.norm();
      if (cos_angle > std::cos(10.0 * M_PI / 180.0) && rho < 0.97) {
        const Eigen::Matrix<double, 6, 1> rest = std::min(rho / (1.0 - rho), 25.0) * step;
        if (dt < config.t_c_m && dr < config.r_c_rad && rest.head<3>().norm() < config.t_c_m &&
            rest.tail<3>().norm() < config.r_c_rad) {
          result.converged = true;
          break;
        }
        T = fromParams(p + rest);
        last_params = params(T);
        last_step.setZero();  // two regular steps before the next extrapolation
        continue;
      }
    }
    last_step = step;
    if (dt < config.t_c_m && dr < config.r_c_rad) {
      result.converged = true;
      break;
    }
  }
  // Final figures at the converged pose.
  double sum2 = 0.0;
  size_t count = 0;
  const Eigen::Isometry3f Tf = T.cast<float>();
  const Eigen::Vector3f origin = side_test ? Eigen::Vector3f(Tf * *source_origin) : Eigen::Vector3f::Zero();
#pragma omp parallel for reduction(+ : sum2, count) schedule(dynamic, 2048)
  for (long i = 0; i < n; ++i) {
    float d2;
    bool horizontal;
    if (pair(i, Tf * source[i], origin, d2, horizontal)) {
      sum2 += d2;
      ++count;
    }
  }
  result.correspondences = count;
  result.overlap = n > 0 ? static_cast<double>(count) / n : 0.0;
  result.rms_m = count > 0 ? std::sqrt(sum2 / count) : 0.0;
  result.T_target_source = T;
  const Eigen::Isometry3d correction = T_init.inverse() * T;
  if (!result.converged) {
    result.failure = "no convergence within " + std::to_string(config.max_iterations) + " iterations";
  } else if (correction.translation().norm() > config.max_correction_m ||
             Eigen::AngleAxisd(correction.linear()).angle() > config.max_correction_rad) {
    result.converged = false;
    result.failure = "the correction of the initial guess (" + std::to_string(correction.translation().norm()) +
                     " m, " + std::to_string(Eigen::AngleAxisd(correction.linear()).angle()) +
                     " rad) exceeds the bound";
  } else if (result.overlap < config.min_overlap || count < static_cast<size_t>(config.min_correspondences)) {
    result.converged = false;
    result.failure = "overlap " + std::to_string(result.overlap) + " below min_overlap " + std::to_string(config.min_overlap);
  }
  if (!result.converged) result.T_target_source = T_init;
  return result;
}

}  // namespace slam
}  // namespace scanstop
