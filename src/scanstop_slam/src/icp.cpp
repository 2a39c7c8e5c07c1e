#include "scanstop_slam/icp.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <unordered_map>
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
  requireInRange("map_spacing_m", min_spacing_m, 0.0, voxel_m, "m");
  if (max_points_per_voxel < 1) throw ConfigError("max_points_per_voxel must be >= 1");
}

namespace {
/// splitmix64's finalizer: spreads neighbouring voxel keys over the whole table.
/// 4 floats as one value: GCC/Clang vector extension, one SSE2 register (x86-64 baseline; 8-wide
/// values without AVX make GCC lower the lane-wise minimum to scalar code).
typedef float Quad __attribute__((vector_size(sizeof(float) * 4)));
#define SCANSTOP_SPLAT4(v) \
  Quad { v, v, v, v }
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
  for (int a = 0; a < 3; ++a)
    views.push_back(static_cast<int8_t>(std::lround(std::clamp(view[a], -1.0f, 1.0f) * 127.0f)));
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

bool VoxelMap::nearest(const Eigen::Vector3f& q, double radius_m, Eigen::Vector3f& out, float& dist2, bool* horizontal,
                       Surface* surface) const {
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
  requireInRange("c_max_m", c_max_m, 0.001, 5.0, "m");
  requireInRange("t_c_m", t_c_m, 1e-9, 1.0, "m");
  requireInRange("r_c_rad", r_c_rad, 1e-9, 1.0, "rad");
  requireInRange("max_iterations", max_iterations, 1, 10000);
  requireInRange("min_correspondences", min_correspondences, 3, 1e9);
  requireInRange("min_overlap", min_overlap, 0.0, 1.0);
  requirePositive("max_correction_m", max_correction_m, "m");
  requirePositive("max_correction_rad", max_correction_rad, "rad");
  requireInRange("degeneracy_ratio", degeneracy_ratio, 0.0, 1.0);
  requireInRange("information_points", information_points, 1e-6, 1e6);
  requireInRange("information_sigma_m", information_sigma_m, 1e-6, 1.0, "m");
}

namespace {
int64_t voxelKey(const Eigen::Vector3f& p, double voxel_m) {
  const auto enc = [voxel_m](float v) {
    return static_cast<int64_t>(std::floor(v / voxel_m) + (1 << 20)) & ((1 << 21) - 1);
  };
  return (enc(p.x()) << 42) | (enc(p.y()) << 21) | enc(p.z());
}
}  // namespace

std::vector<Eigen::Vector3f> voxelCentroids(const std::vector<Eigen::Vector3f>& points, double voxel_m) {
  if (voxel_m <= 0.0) return voxelDownsample(points, voxel_m);
  std::unordered_map<int64_t, uint32_t> slot;
  slot.reserve(points.size());
  std::vector<Eigen::Vector3d> sum;
  std::vector<uint32_t> count;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const auto it = slot.emplace(voxelKey(p, voxel_m), static_cast<uint32_t>(sum.size()));
    if (it.second) {
      sum.push_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    sum[it.first->second] += p.cast<double>();
    ++count[it.first->second];
  }
  std::vector<Eigen::Vector3f> out(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) out[i] = (sum[i] / count[i]).cast<float>();
  return out;
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
    if (seen.insert(voxelKey(p, voxel_m)).second) out.push_back(p);
  }
  return out;
}

void VoxelDownsampler::add(const std::vector<Eigen::Vector3f>& points) {
  if (voxel_m_ <= 0.0) {
    for (const auto& p : points)
      if (p.allFinite()) points_.push_back(p);
    return;
  }
  for (const auto& p : points)
    if (p.allFinite() && seen_.insert(voxelKey(p, voxel_m_)).second) points_.push_back(p);
}

std::string toString(IcpMethod method) {
  return method == IcpMethod::point_to_plane ? "point_to_plane" : "point_to_point";
}

IcpMethod parseIcpMethod(const std::string& text, const std::string& name) {
  requireOneOf(name, text, {"point_to_point", "point_to_plane"});
  return text == "point_to_plane" ? IcpMethod::point_to_plane : IcpMethod::point_to_point;
}

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Pose parameters: translation and rotation vector (rotation scaled by 1 m, so that both parts
/// weigh alike for a scene of metres).
Vector6d params(const Eigen::Isometry3d& T) {
  Vector6d p;
  const Eigen::AngleAxisd aa(T.linear());
  p << T.translation(), aa.axis() * aa.angle();
  return p;
}

Eigen::Isometry3d fromParams(const Vector6d& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const double angle = p.tail<3>().norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, p.tail<3>() / angle).toRotationMatrix();
  T.translation() = p.head<3>();
  return T;
}

/// The solved pose parameters among the six of params(): 3dof (t_x, t_y, w_z) or all.
constexpr int kThreeDof[3] = {0, 1, 5};
Eigen::MatrixXd reduce(const Matrix6d& H, bool six_dof) {
  if (six_dof) return H;
  Eigen::MatrixXd out(3, 3);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = H(kThreeDof[r], kThreeDof[c]);
  return out;
}
Eigen::VectorXd reduce(const Vector6d& v, bool six_dof) {
  if (six_dof) return v;
  return Eigen::Vector3d(v(0), v(1), v(5));
}
/// The inverse of reduce() for a vector: the parameters 3dof does not solve are zero.
Vector6d expand(const Eigen::VectorXd& v, bool six_dof) {
  if (six_dof) return v;
  Vector6d out = Vector6d::Zero();
  for (int r = 0; r < 3; ++r) out(kThreeDof[r]) = v(r);
  return out;
}

/// The correspondence step: per source point the nearest map point within c_max that may pair
/// with it (IcpConfig::same_side, ignore_horizontal, unique_matches), with the map's plane there.
/// It keeps the per-point state of the exact search shortcuts from one search to the next.
class Correspondences {
 public:
  Correspondences(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source, const IcpConfig& config,
                  const Eigen::Vector3f* source_origin, bool normals)
      : target_(target),
        source_(source),
        n_(static_cast<long>(source.size())),
        c_max_(config.c_max_m),
        reuse_(config.reuse_search_bounds),
        side_test_(config.same_side && source_origin != nullptr),
        normals_(normals),
        source_origin_(source_origin),
        matched(source.size()),
        has(source.size(), 0),
        horizontal(source.size(), 0),
        normal(source.size(), Eigen::Vector3f::Zero()),
        dist2_(config.unique_matches ? source.size() : 0),
        hit_(source.size(), 0),
        bounded_(source.size(), 0),
        anchor_(reuse_ ? source.size() : 0),
        lower_(reuse_ ? source.size() : 0) {}

  /// The search at pose T (has, matched, horizontal; normal when asked for normals: the map's
  /// plane normal of a pair, zero where its voxel is not planar). skip_horizontal drops pairs on
  /// horizontal voxels; unique keeps one source point per map point. Returns the number of pairs.
  size_t find(const Eigen::Isometry3d& T, bool skip_horizontal, bool unique) {
    const Eigen::Isometry3f Tf = T.cast<float>();
    const Eigen::Vector3f origin = side_test_ ? Eigen::Vector3f(Tf * *source_origin_) : Eigen::Vector3f::Zero();
    // Correspondences (parallel): nearest map point within c_max of each transformed source point.
#pragma omp parallel for schedule(dynamic, 2048)
    for (long i = 0; i < n_; ++i) {
      float d2;
      bool horiz = false;
      Surface s;
      has[i] =
          pair(i, Tf * source_[i], origin, d2, horiz, normals_ ? &s : nullptr) && !(skip_horizontal && horiz) ? 1 : 0;
      horizontal[i] = horiz ? 1 : 0;
      if (normals_) normal[i] = has[i] && s.planar ? s.normal : Eigen::Vector3f::Zero();
      if (unique) dist2_[i] = d2;
    }
    if (unique) {
      // Of the source points paired with one map point (equal coordinates: the same stored point)
      // only the nearest keeps it (ties: the lower index, so the result does not depend on threads).
      order_.clear();
      for (long i = 0; i < n_; ++i)
        if (has[i]) order_.push_back(static_cast<uint32_t>(i));
      std::sort(order_.begin(), order_.end(), [&](uint32_t a, uint32_t b) {
        const Eigen::Vector3f& p = matched[a];
        const Eigen::Vector3f& q = matched[b];
        if (p.x() != q.x()) return p.x() < q.x();
        if (p.y() != q.y()) return p.y() < q.y();
        if (p.z() != q.z()) return p.z() < q.z();
        return dist2_[a] != dist2_[b] ? dist2_[a] < dist2_[b] : a < b;
      });
      for (size_t k = 1; k < order_.size(); ++k)
        if (matched[order_[k]] == matched[order_[k - 1]]) has[order_[k]] = 0;
    }
    size_t count = 0;
    for (long i = 0; i < n_; ++i) count += has[i];
    return count;
  }

  /// The final figures at pose T: every pair (no horizontal skip, no uniqueness), the sum of their
  /// squared distances and their number; has, matched, horizontal and normal as find() sets them.
  void final(const Eigen::Isometry3d& T, double& sum2, size_t& count) {
    sum2 = 0.0;
    count = 0;
    const Eigen::Isometry3f Tf = T.cast<float>();
    const Eigen::Vector3f origin = side_test_ ? Eigen::Vector3f(Tf * *source_origin_) : Eigen::Vector3f::Zero();
#pragma omp parallel for reduction(+ : sum2, count) schedule(dynamic, 2048)
    for (long i = 0; i < n_; ++i) {
      float d2;
      bool horiz = false;
      Surface s;
      has[i] = pair(i, Tf * source_[i], origin, d2, horiz, &s) ? 1 : 0;
      horizontal[i] = horiz ? 1 : 0;
      normal[i] = has[i] && s.planar ? s.normal : Eigen::Vector3f::Zero();
      if (has[i]) {
        sum2 += d2;
        ++count;
      }
    }
  }

 private:
  // Exact shortcuts of the correspondence search, from what the last search of each point found.
  // A hit (its nearest map point m within c_max): m is a map point, so the nearest one now is no
  // farther than |q - m|, and that radius (padded against rounding) replaces c_max. A miss is
  // searched out to c_max + miss_margin; the distance of the nearest point found beyond c_max
  // (or that radius when there is none) is a lower bound at the searched position (anchor), and
  // while the point has moved less than that bound minus c_max from there it still has no match
  // within c_max and is not searched at all. Either way the result is the nearest map point within
  // c_max, as the full search finds it (poses identical up to exact distance ties).
  /// The nearest map point within c_max of q (point i transformed); its squared distance in d2.
  bool correspond(long i, const Eigen::Vector3f& q, float& d2, bool& horiz, Surface* surface) {
    if (!reuse_) return target_.nearest(q, c_max_, matched[i], d2, &horiz, surface);
    const float c_max_f = static_cast<float>(c_max_);
    const float c_max2_f = static_cast<float>(c_max_ * c_max_);  // nearest()'s own bound for radius c_max
    const double miss_margin = 0.5 * c_max_;
    // Rounding allowance of the float distances and of nearest()'s voxel boxes [m].
    const float eps = 1e-4f + 1e-6f * q.cwiseAbs().maxCoeff();
    if (hit_[i]) {
      const float d_last = (q - matched[i]).norm();
      // matched[i] lies within the radius, so this finds a point (the nearest one).
      if (d_last < c_max_f &&
          target_.nearest(q, std::min(c_max_, static_cast<double>(d_last + eps)), matched[i], d2, &horiz, surface))
        return true;
    } else if (bounded_[i] && lower_[i] - (q - anchor_[i]).norm() >= c_max_f + eps) {
      return false;
    }
    const double radius = c_max_ + miss_margin;
    Eigen::Vector3f m;
    const bool found = target_.nearest(q, radius, m, d2, &horiz, surface);
    if (found && d2 < c_max2_f) {
      matched[i] = m;
      hit_[i] = 1;
      bounded_[i] = 0;
      return true;
    }
    hit_[i] = 0;
    bounded_[i] = 1;
    anchor_[i] = q;
    lower_[i] = found ? std::sqrt(d2) : static_cast<float>(radius);
    return false;
  }
  /// Same side (IcpConfig::same_side): where the map point's voxel is one plane and both points'
  /// viewing directions are known, they must have been seen from the same side of it, each clear of
  /// the plane (more than ~6 deg). A point seen along the plane has no side: paired with a point
  /// seen clearly it may be the other face of a thin wall. room_10x8 seed 7: the robot in the door,
  /// 11 cm from the corridor's face of the 10 cm wall, saw that face at grazing angles; its points
  /// paired with the room's face and held the scan 6.2 cm into the room, registered alone against
  /// the earlier scans at their true poses; 0.2 cm when such pairs are no pairs (docs/decisions.md).
  static bool sameSide(const Eigen::Vector3f& q, const Eigen::Vector3f& origin, const Surface& s) {
    if (!s.planar) return true;
    const float map_side = s.normal.dot(s.view);
    const Eigen::Vector3f to_sensor = origin - q;
    const float n = to_sensor.norm();
    if (!(n > 0.0f) || s.view.squaredNorm() == 0.0f) return true;  // a view unknown: no test
    const float source_side = s.normal.dot(to_sensor) / n;
    constexpr float kClear = 0.1f;
    const bool map_clear = std::abs(map_side) > kClear, source_clear = std::abs(source_side) > kClear;
    if (map_clear != source_clear) return false;
    return !((map_side > kClear && source_side < -kClear) || (map_side < -kClear && source_side > kClear));
  }
  /// The nearest map point within c_max that may pair with point i (at q; origin: the source's
  /// sensor in the map frame); surface (when given) its plane.
  bool pair(long i, const Eigen::Vector3f& q, const Eigen::Vector3f& origin, float& d2, bool& horiz, Surface* surface) {
    Surface local;
    Surface* s = surface ? surface : (side_test_ ? &local : nullptr);
    if (!correspond(i, q, d2, horiz, s)) return false;
    return !side_test_ || sameSide(q, origin, *s);
  }

  const VoxelMap& target_;
  const std::vector<Eigen::Vector3f>& source_;
  const long n_;
  const double c_max_;
  const bool reuse_;
  const bool side_test_;
  const bool normals_;
  const Eigen::Vector3f* source_origin_;

 public:
  std::vector<Eigen::Vector3f> matched;  ///< the pair's map point (valid where has)
  std::vector<uint8_t> has;              ///< point i has a pair
  std::vector<uint8_t> horizontal;       ///< its map point's voxel is horizontal
  std::vector<Eigen::Vector3f> normal;   ///< its map point's plane normal (zero: not planar)

 private:
  std::vector<float> dist2_;      // of each pair (unique_matches)
  std::vector<uint32_t> order_;   // pairs sorted by map point
  std::vector<uint8_t> hit_;      // last search: a map point within c_max (matched[i])
  std::vector<uint8_t> bounded_;  // last search: a miss with a lower bound
  std::vector<Eigen::Vector3f> anchor_;
  std::vector<float> lower_;  // nearest map point distance at anchor >= this [m]
};

/// One step of thesis Algorithm 4 from the `count` pairs at pose T: the update delta, applied as
/// delta * T (map frame). Centroids and correlation in double, relative to the current pose (the
/// transformed source points are recomputed in double: float rounding would keep the
/// per-iteration change from ever falling below tight t_c / r_c).
Eigen::Isometry3d pointToPointStep(const std::vector<Eigen::Vector3f>& source, const Correspondences& pairs,
                                   const Eigen::Isometry3d& T, size_t count, bool six_dof) {
  const long n = static_cast<long>(source.size());
  Eigen::Vector3d cd = Eigen::Vector3d::Zero(), cm = Eigen::Vector3d::Zero();
  for (long i = 0; i < n; ++i) {
    if (!pairs.has[i]) continue;
    cd += T * source[i].cast<double>();
    cm += pairs.matched[i].cast<double>();
  }
  cd /= count;
  cm /= count;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (long i = 0; i < n; ++i) {
    if (!pairs.has[i]) continue;
    H += (T * source[i].cast<double>() - cd) * (pairs.matched[i].cast<double>() - cm).transpose();
  }
  // Rotation from the SVD of the correlation matrix (Algorithm 4, lines 9-11): R = V U^T.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (six_dof) {
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
  if (!six_dof) t.z() = 0.0;
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = R;
  delta.translation() = t;
  return delta;
}

/// Gauss-Newton normal equations of the point-to-plane residuals r = n . (T p - m) over the pairs
/// with a planar normal (skip_horizontal: not on horizontal voxels), for the perturbation
/// T * [R(w), t] (params() order): J = [R^T n, p x R^T n], H = sum J^T J, g = sum J^T r. Also the
/// first and second moments of those pairs' source points (for normalization()).
struct PlaneEquations {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  size_t count = 0;
  Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_p2 = Eigen::Vector3d::Zero();  ///< per axis
};
PlaneEquations planeEquations(const std::vector<Eigen::Vector3f>& source, const Correspondences& pairs,
                              const Eigen::Isometry3d& T, bool skip_horizontal) {
  PlaneEquations e;
  const Eigen::Matrix3d Rt = T.linear().transpose();
  for (size_t i = 0; i < source.size(); ++i) {
    if (!pairs.has[i] || (skip_horizontal && pairs.horizontal[i])) continue;
    const Eigen::Vector3d n = pairs.normal[i].cast<double>();
    if (n.squaredNorm() == 0.0) continue;  // not planar
    const Eigen::Vector3d p = source[i].cast<double>();
    const double r = n.dot(T * p - pairs.matched[i].cast<double>());
    const Eigen::Vector3d nb = Rt * n;
    Vector6d J;
    J << nb, p.cross(nb);
    e.H.noalias() += J * J.transpose();
    e.g += J * r;
    e.sum_p += p;
    e.sum_p2 += p.cwiseProduct(p);
    ++e.count;
  }
  return e;
}

/// The normalized pose parameters of the eigen-analysis: translation, and rotation about the
/// pairs' centroid c (source frame) times their RMS distance L from it (3dof: horizontal
/// distance), both in metres. Returns A with (pose parameters) = A (normalized parameters):
/// t = t' + c x w, w = u / L. So the eigenvalues compare geometry, not units or the place of the
/// source frame's origin (a rotation about a far origin is mostly a translation).
Eigen::MatrixXd normalization(const PlaneEquations& e, bool six_dof) {
  const double n = static_cast<double>(std::max<size_t>(e.count, 1));
  const Eigen::Vector3d c = e.sum_p / n;
  const Eigen::Vector3d var = (e.sum_p2 / n - c.cwiseProduct(c)).cwiseMax(0.0);
  double L = std::sqrt(six_dof ? var.sum() : var.x() + var.y());
  if (!(L > 1e-9)) L = 1.0;
  if (!six_dof) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
    A(0, 2) = c.y() / L;  // (c x w z)_x = c_y w
    A(1, 2) = -c.x() / L;
    A(2, 2) = 1.0 / L;
    return A;
  }
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(6, 6);
  Eigen::Matrix3d cx;
  cx << 0, -c.z(), c.y(), c.z(), 0, -c.x(), -c.y(), c.x(), 0;
  A.topRightCorner(3, 3) = cx / L;
  A.bottomRightCorner(3, 3) = Eigen::Matrix3d::Identity() / L;
  return A;
}

/// Eigen-decomposition of an information matrix H (pose parameters) in the normalized parameters
/// of A (A^T H A, ascending), and its weak directions: eigenvalues below ratio times the largest
/// (the first `weak` columns).
struct Spectrum {
  Eigen::MatrixXd A;
  Eigen::VectorXd values;
  Eigen::MatrixXd vectors;
  int weak = 0;
  double largest() const { return values(values.size() - 1); }
};
Spectrum spectrum(const Eigen::MatrixXd& H, const Eigen::MatrixXd& A, double ratio) {
  Spectrum s;
  s.A = A;
  const Eigen::MatrixXd Hn = A.transpose() * H * A;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (Hn + Hn.transpose()));
  s.values = eig.eigenvalues();
  s.vectors = eig.eigenvectors();
  const double bound = ratio * s.largest();
  while (s.weak < s.values.size() && s.values(s.weak) < bound) ++s.weak;
  return s;
}
Spectrum spectrum(const PlaneEquations& e, bool six_dof, double ratio) {
  return spectrum(reduce(e.H, six_dof), normalization(e, six_dof), ratio);
}

/// IcpResult's information fields from the point-to-plane equations at the result.
void summarize(IcpResult& result, const PlaneEquations& e, bool six_dof, double ratio) {
  result.information_pairs = e.count;
  result.information.resize(0, 0);
  result.eigenvalues.resize(0);
  result.weak_direction.resize(0);
  result.condition = std::numeric_limits<double>::quiet_NaN();
  result.degenerate = false;
  result.weak_directions = 0;
  if (e.count == 0) return;
  result.information = reduce(e.H, six_dof);
  const Spectrum s = spectrum(e, six_dof, ratio);
  result.eigenvalues = s.values;
  const double smallest = s.values(0);
  result.condition = smallest > 0.0 ? s.largest() / smallest : std::numeric_limits<double>::infinity();
  Eigen::VectorXd v = (s.A * s.vectors.col(0)).normalized();  // in the pose parameters
  Eigen::Index k;
  v.cwiseAbs().maxCoeff(&k);
  if (v(k) < 0.0) v = -v;
  result.weak_direction = v;
  result.weak_directions = s.weak;
  result.degenerate = s.weak > 0;
}

/// Solution remapping, the hard form: T's correction from `keep` goes back to zero along the weak
/// directions of s (their span, W = A V_weak); the well-constrained part of the result stays.
/// "Back to the guess" is measured at the source frame's origin, the robot, where the odometry
/// prior holds its position (a radian weighs as L metres, L the pairs' RMS distance from their
/// centroid): not in the normalized parameters, whose rotation turns about the pairs' centroid.
/// There, a yaw error of the guess that the registration corrected counted as a translation of the
/// centroid, and restoring the centroid moved the robot along the weak axis (turtlebot3_house
/// seed 4 scan 60: a 2.3 deg yaw error of the odometry leg, the centroid 1.4 m away, slid the
/// robot 5.7 cm along a corridor, 9.2 cm from the truth).
Eigen::Isometry3d remapToPrior(const Eigen::Isometry3d& T, const Spectrum& s, const Eigen::Isometry3d& keep,
                               bool six_dof) {
  const Eigen::VectorXd back = reduce(params(T.inverse() * keep), six_dof);
  const Eigen::MatrixXd W = s.A * s.vectors.leftCols(s.weak);
  const Eigen::Index dims = back.size(), rotations = six_dof ? 3 : 1;
  const double L = 1.0 / s.A(dims - 1, dims - 1);
  Eigen::VectorXd metric = Eigen::VectorXd::Ones(dims);
  metric.tail(rotations).setConstant(L * L);
  const Eigen::MatrixXd WtM = W.transpose() * metric.asDiagonal();
  const Eigen::VectorXd alpha = (WtM * W).ldlt().solve(WtM * back);
  return T * fromParams(expand(W * alpha, six_dof));
}

/// The weighed form (icp()'s prior_information): along the weak directions of s only, the step (in
/// the normalized parameters of s) that minimizes the pairs' point-to-plane residuals, weighted as
/// IcpConfig's information_points / information_sigma_m say (g_n: their gradient in the
/// normalized parameters, count pairs), plus the prior's Mahalanobis distance; offset_n: the pose
/// relative to the prior in those parameters (after the strong directions' step). The strong
/// directions are left to the pairs alone: there the pairs know far more than odometry, and
/// weighing the prior there pulled well-conditioned registrations centimetres towards the guess
/// (office_loop seed 2, isolated: RMS 1.0 -> 1.3 cm) as correspondences changed under it.
Eigen::VectorXd weakPriorStep(const Spectrum& s, const Eigen::VectorXd& g_n, size_t count,
                              const Eigen::VectorXd& offset_n, const Eigen::MatrixXd& prior_information,
                              const IcpConfig& config) {
  const double w = config.information_points / (static_cast<double>(std::max<size_t>(count, 1)) *
                                                config.information_sigma_m * config.information_sigma_m);
  const Eigen::MatrixXd V = s.vectors.leftCols(s.weak);
  const Eigen::MatrixXd Ln = s.A.transpose() * prior_information * s.A;  // the prior in normalized parameters
  const Eigen::MatrixXd M = w * Eigen::MatrixXd(s.values.head(s.weak).asDiagonal()) + V.transpose() * Ln * V;
  const Eigen::VectorXd b = w * V.transpose() * g_n + V.transpose() * Ln * offset_n;
  return -V * M.ldlt().solve(b);
}

/// IcpConfig::prior_all_directions: one Gauss-Newton step of the pairs' point-to-plane residuals,
/// weighted as information_points / information_sigma_m say, plus the prior's Mahalanobis
/// distance from T's offset to the prior, in every direction: the reduced step d of
/// T * fromParams(expand(d)).
Eigen::VectorXd weightedStep(const PlaneEquations& e, const Eigen::Isometry3d& T, const Eigen::Isometry3d& prior,
                             const Eigen::MatrixXd& prior_information, const IcpConfig& config) {
  const double w = config.information_points / (static_cast<double>(std::max<size_t>(e.count, 1)) *
                                                config.information_sigma_m * config.information_sigma_m);
  const Eigen::MatrixXd H = reduce(e.H, config.six_dof) * w + prior_information;
  const Eigen::VectorXd g =
      reduce(e.g, config.six_dof) * w + prior_information * reduce(params(prior.inverse() * T), config.six_dof);
  return -H.ldlt().solve(g);
}

/// The pose relative to the prior (keep^-1 T) in the normalized parameters of s.
Eigen::VectorXd offsetFromPrior(const Eigen::Isometry3d& T, const Eigen::Isometry3d& keep, const Spectrum& s,
                                bool six_dof) {
  return s.A.fullPivLu().solve(reduce(params(keep.inverse() * T), six_dof));
}

}  // namespace

namespace {

/// A step small enough to call the registration converged (t_c, r_c).
bool smallStep(const Vector6d& d6, const IcpConfig& config) {
  return d6.head<3>().norm() < config.t_c_m && d6.tail<3>().norm() < config.r_c_rad;
}

/// One Gauss-Newton step of point-to-plane ICP from the pairs' equations at T, as the 6-vector update
/// T * fromParams(step). With the prior weighed in every direction: the weighted objective's step.
/// Otherwise H d = -g, solved in H's eigenbasis: with degeneracy_remap (or a prior) the weak directions
/// get no step of their own (solution remapping: the step projected onto the well-constrained
/// subspace; *remapped is set) and, with prior information, what their few pairs and the prior say
/// together; without, only numerically null directions (< 1e-12 of the largest) are left out, so that
/// a singular H gives a finite step. (In the normalized parameters of the eigen-analysis:
/// H_n = A^T H A, g_n = A^T g, d = A d_n.)
Vector6d planeStep(const PlaneEquations& eq, const Eigen::Isometry3d& T, const Eigen::Isometry3d& keep,
                   const IcpConfig& config, const Eigen::MatrixXd* prior_information, bool* remapped) {
  if (prior_information && config.prior_all_directions)
    return expand(weightedStep(eq, T, keep, *prior_information, config), config.six_dof);
  const Spectrum s = spectrum(eq, config.six_dof, config.degeneracy_ratio);
  const Eigen::VectorXd g = s.A.transpose() * reduce(eq.g, config.six_dof);
  const int first = config.degeneracy_remap || prior_information ? s.weak : 0;
  if (first > 0) *remapped = true;
  Eigen::VectorXd d = Eigen::VectorXd::Zero(g.size());
  for (int k = first; k < s.values.size(); ++k)
    if (s.values(k) > 1e-12 * s.largest()) d -= s.vectors.col(k) * (s.vectors.col(k).dot(g) / s.values(k));
  if (prior_information && first > 0)
    d += weakPriorStep(s, g, eq.count, offsetFromPrior(T, keep, s, config.six_dof) + d, *prior_information, config);
  return expand(s.A * d, config.six_dof);
}

/// Point-to-point ICP's steps, with Besl and McKay's accelerated ICP (1992, section IV.C), linear
/// form: point-to-point ICP creeps towards the optimum in ever smaller steps along a nearly constant
/// direction, so a small step alone does not mean it has arrived (the thesis' criterion stops tenths
/// of a degree short). When two successive steps point the same way (within 10 deg) and shrink by the
/// ratio rho, the rest of the geometric series, step * rho / (1 - rho) (at most 25 steps), is taken at
/// once, and convergence is declared only when that rest is below t_c and r_c too.
class PointToPointSteps {
 public:
  explicit PointToPointSteps(const Eigen::Isometry3d& T) : last_params_(params(T)) {}

  /// Applies one step `delta` (left-multiplied) to T, and the extrapolated rest where it creeps.
  /// Returns true when the registration has converged.
  bool apply(const Eigen::Isometry3d& delta, Eigen::Isometry3d& T, const IcpConfig& config) {
    T = delta * T;
    const double dt = delta.translation().norm();
    const double dr = Eigen::AngleAxisd(delta.linear()).angle();
    const Vector6d p = params(T);
    const Vector6d step = p - last_params_;
    last_params_ = p;
    if (config.accelerate && last_step_.norm() > 0.0 && step.norm() > 0.0 && p.tail<3>().norm() < 3.0) {
      const double cos_angle = step.dot(last_step_) / (step.norm() * last_step_.norm());
      const double rho = step.norm() / last_step_.norm();
      if (cos_angle > std::cos(10.0 * M_PI / 180.0) && rho < 0.97) {
        const Vector6d rest = std::min(rho / (1.0 - rho), 25.0) * step;
        if (dt < config.t_c_m && dr < config.r_c_rad && rest.head<3>().norm() < config.t_c_m &&
            rest.tail<3>().norm() < config.r_c_rad)
          return true;
        T = fromParams(p + rest);
        last_params_ = params(T);
        last_step_.setZero();  // two regular steps before the next extrapolation
        return false;
      }
    }
    last_step_ = step;
    return dt < config.t_c_m && dr < config.r_c_rad;
  }

 private:
  Vector6d last_step_ = Vector6d::Zero();
  Vector6d last_params_;
};

/// The converged pose's weak directions: point-to-point moved along them as freely as along the
/// others, an earlier stage given as prior may have, and point-to-plane's steps were projected onto
/// the strong directions of each iteration's pairs, which turn as the pairs change: undo that. Along
/// the weak eigenvectors of the final pairs the correction goes back to the prior (remapToPrior),
/// or, with prior_information, to where the weak directions' pairs and the prior weigh it
/// (weakPriorStep); the well-constrained part of the result stays. Records the prior's gain.
Eigen::Isometry3d settleWeakDirections(const PlaneEquations& final_eq, const Eigen::Isometry3d& T,
                                       const Eigen::Isometry3d& keep, const IcpConfig& config,
                                       const Eigen::MatrixXd* prior_information, IcpResult& result) {
  const Spectrum s = spectrum(final_eq, config.six_dof, config.degeneracy_ratio);
  const Eigen::Isometry3d remapped = remapToPrior(T, s, keep, config.six_dof);
  if (!prior_information) return remapped;
  const Eigen::VectorXd g_n = s.A.transpose() * reduce(final_eq.g, config.six_dof);
  const Eigen::VectorXd step =
      weakPriorStep(s, g_n, final_eq.count, offsetFromPrior(T, keep, s, config.six_dof), *prior_information, config);
  const Eigen::Isometry3d settled = T * fromParams(expand(s.A * step, config.six_dof));
  const Eigen::Isometry3d gain = remapped.inverse() * settled;
  result.weak_gain_m = gain.translation().norm();
  result.weak_gain_rad = Eigen::AngleAxisd(gain.linear()).angle();
  return settled;
}

/// The verdict on a converged registration: the correction of the guess within its bounds, enough
/// overlap and pairs; a failed one keeps T_init.
void judge(const Eigen::Isometry3d& T_init, const IcpConfig& config, size_t count, IcpResult& result) {
  const Eigen::Isometry3d correction = T_init.inverse() * result.T_target_source;
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
    result.failure =
        "overlap " + std::to_string(result.overlap) + " below min_overlap " + std::to_string(config.min_overlap);
  }
  if (!result.converged) result.T_target_source = T_init;
}

}  // namespace

IcpResult icp(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source, const Eigen::Isometry3d& T_init,
              const IcpConfig& config, const Eigen::Vector3f* source_origin, const Eigen::Isometry3d* prior,
              const Eigen::MatrixXd* prior_information) {
  const long dims = config.six_dof ? 6 : 3;
  if (prior_information &&
      (prior_information->rows() != dims || prior_information->cols() != dims || !prior_information->allFinite()))
    throw std::invalid_argument("icp: the prior information must be a finite " + std::to_string(dims) + "x" +
                                std::to_string(dims) + " matrix");
  const Eigen::Isometry3d& keep = prior ? *prior : T_init;
  IcpResult result;
  Eigen::Isometry3d T = T_init;
  const long n = static_cast<long>(source.size());
  const bool plane = config.method == IcpMethod::point_to_plane;
  Correspondences pairs(target, source, config, source_origin, plane);
  const bool skip_horizontal = !config.six_dof && config.ignore_horizontal;
  PointToPointSteps point_to_point(T);
  for (int it = 1; it <= config.max_iterations; ++it) {
    result.iterations = it;
    const size_t count = pairs.find(T, skip_horizontal, config.unique_matches);
    result.correspondences = count;
    result.overlap = n > 0 ? static_cast<double>(count) / n : 0.0;
    // Point-to-plane: the pairs with a planar normal are the ones that count.
    const PlaneEquations eq = plane ? planeEquations(source, pairs, T, skip_horizontal) : PlaneEquations();
    const size_t used = plane ? eq.count : count;
    if (used < static_cast<size_t>(config.min_correspondences)) {
      result.failure = "too few " + std::string(plane ? "planar " : "") + "correspondences (" + std::to_string(used) +
                       " < " + std::to_string(config.min_correspondences) +
                       ") within c_max_m = " + std::to_string(config.c_max_m) + " m";
      result.T_target_source = T_init;
      return result;
    }
    if (plane) {
      const Vector6d d6 = planeStep(eq, T, keep, config, prior_information, &result.remapped);
      T = T * fromParams(d6);
      result.converged = smallStep(d6, config);
    } else {
      result.converged = point_to_point.apply(pointToPointStep(source, pairs, T, count, config.six_dof), T, config);
    }
    if (result.converged) break;
  }
  // Final figures at the converged pose, and the information matrix of its pairs.
  double sum2 = 0.0;
  size_t count = 0;
  pairs.final(T, sum2, count);
  PlaneEquations final_eq = planeEquations(source, pairs, T, skip_horizontal);
  summarize(result, final_eq, config.six_dof, config.degeneracy_ratio);
  const auto refresh = [&] {  // the figures again at a moved T
    pairs.final(T, sum2, count);
    final_eq = planeEquations(source, pairs, T, skip_horizontal);
    summarize(result, final_eq, config.six_dof, config.degeneracy_ratio);
  };
  if (result.converged && prior_information && config.prior_all_directions) {
    if (!plane) {  // point-to-point's optimum, combined with the prior by one step of the weighted objective
      T = T * fromParams(expand(weightedStep(final_eq, T, keep, *prior_information, config), config.six_dof));
      refresh();
    }
    result.remapped = result.degenerate;
  } else if (result.converged && result.weak_directions > 0 && (prior_information || config.degeneracy_remap)) {
    T = settleWeakDirections(final_eq, T, keep, config, prior_information, result);
    result.remapped = true;
    refresh();
  }
  result.correspondences = count;
  result.overlap = n > 0 ? static_cast<double>(count) / n : 0.0;
  result.rms_m = count > 0 ? std::sqrt(sum2 / count) : 0.0;
  result.T_target_source = T;
  judge(T_init, config, count, result);
  return result;
}

}  // namespace slam
}  // namespace scanstop
