#include "scanstop_mesher/decimate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "scanstop_common/config.h"
#include "scanstop_mesher/mesh_analysis.h"

namespace scanstop {
namespace mesher {

void DecimateConfig::validate() const {
  requireInRange("max_error_m", max_error_m, 0.0, 0.1, "m");
  requireInRange("min_normal_cos", min_normal_cos, -1.0, 1.0);
  requireInRange("threads", threads, 1, 2);
}

namespace {

/// A symmetric 4x4 quadric [A b; b^T c] of planes n.x + d = 0: the sum of (n.x + d)^2.
struct Quadric {
  double aa = 0, ab = 0, ac = 0, ad = 0, bb = 0, bc = 0, bd = 0, cc = 0, cd = 0, dd = 0;
  double planes = 0;  ///< planes summed
  void addPlane(const Eigen::Vector3d& n, double d) {
    planes += 1;
    aa += n.x() * n.x(), ab += n.x() * n.y(), ac += n.x() * n.z(), ad += n.x() * d;
    bb += n.y() * n.y(), bc += n.y() * n.z(), bd += n.y() * d;
    cc += n.z() * n.z(), cd += n.z() * d, dd += d * d;
  }
  Quadric& operator+=(const Quadric& o) {
    aa += o.aa, ab += o.ab, ac += o.ac, ad += o.ad, bb += o.bb, bc += o.bc, bd += o.bd, cc += o.cc, cd += o.cd,
        dd += o.dd, planes += o.planes;
    return *this;
  }
  Eigen::Matrix3d A() const {
    Eigen::Matrix3d m;
    m << aa, ab, ac, ab, bb, bc, ac, bc, cc;
    return m;
  }
  Eigen::Vector3d b() const { return Eigen::Vector3d(ad, bd, cd); }
  /// Mean squared distance of x to the planes [m^2].
  double eval(const Eigen::Vector3d& x) const {
    if (planes <= 0) return 0.0;
    return std::max(0.0, x.dot(A() * x) + 2.0 * b().dot(x) + dd) / planes;
  }
};

/// One candidate collapse: v goes into u; stale once either vertex changed since it was made.
struct Candidate {
  int u, v;
  uint32_t version_u, version_v;
};
/// Candidates by cost, cheapest first to within 1/kBuckets of the bound: a bucket queue on
/// sqrt(cost) / max_error (O(1) push and pop, and the candidates of one neighbourhood stay together
/// in memory; a binary heap of the millions of candidates spent half the time in cache misses).
/// Within a bucket the last pushed goes first (deterministic).
class BucketQueue {
 public:
  static constexpr int kBuckets = 4096;
  explicit BucketQueue(double max_error) : scale_(kBuckets / max_error), buckets_(kBuckets) {}
  void push(double cost, uint32_t slot) {
    const double x = std::sqrt(std::max(0.0, cost)) * scale_;
    const int b = x < kBuckets - 1 ? static_cast<int>(x) : kBuckets - 1;
    buckets_[b].push_back(slot);
    lowest_ = std::min(lowest_, b);
  }
  /// False when empty.
  bool pop(uint32_t* slot) {
    while (lowest_ < kBuckets && buckets_[lowest_].empty()) ++lowest_;
    if (lowest_ >= kBuckets) return false;
    *slot = buckets_[lowest_].back();
    buckets_[lowest_].pop_back();
    return true;
  }

 private:
  double scale_;
  std::vector<std::vector<uint32_t>> buckets_;
  int lowest_ = kBuckets;
};

/// Twice the area over the summed squared edges, scaled so an equilateral triangle gives 1.
double quality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double s = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (s <= 0.0) return 0.0;
  return 2.0 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / s;
}

class Decimator {
 public:
  /// `pinned`: vertices that must stay as well (by index; may be empty).
  Decimator(TriangleMesh& mesh, const DecimateConfig& config, std::vector<char> pinned = {})
      : mesh_(mesh), config_(config), pinned_(std::move(pinned)) {}

  /// Per vertex of the mesh after run(): its index before.
  const std::vector<int>& origin() const { return origin_; }

  DecimateStats run() {
    const auto t0 = std::chrono::steady_clock::now();
    stats_.faces_before = mesh_.faces.size();
    stats_.vertices_before = mesh_.vertices.size();
    setUp();
    const double bound = config_.max_error_m * config_.max_error_m;
    while (alive_faces_ > config_.max_faces) {
      uint32_t slot;
      if (!queue_.pop(&slot)) break;
      const Candidate c = pool_[slot];
      free_.push_back(slot);
      if (!alive_vertex_[c.u] || !alive_vertex_[c.v] || version_[c.u] != c.version_u || version_[c.v] != c.version_v)
        continue;
      Eigen::Vector3d p;
      const double cost = placement(c.u, c.v, &p);
      if (cost > bound) continue;
      if (!collapsible(c.u, c.v, p)) {
        ++stats_.refused;
        continue;
      }
      collapse(c.u, c.v, p);
      stats_.max_error_m = std::max(stats_.max_error_m, std::sqrt(cost));
      ++stats_.collapses;
    }
    compact();
    stats_.faces_after = mesh_.faces.size();
    stats_.vertices_after = mesh_.vertices.size();
    stats_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats_;
  }

 private:
  void setUp() {
    const size_t nv = mesh_.vertices.size();
    pos_.resize(nv);
    for (size_t i = 0; i < nv; ++i) pos_[i] = mesh_.vertices[i].cast<double>();
    quadric_.assign(nv, Quadric());
    faces_of_.assign(nv, {});
    alive_vertex_.assign(nv, 1);
    version_.assign(nv, 0);
    locked_.assign(nv, 0);
    mark_.assign(nv, 0u);
    for (size_t i = 0; i < pinned_.size() && i < nv; ++i) locked_[i] = pinned_[i];
    alive_face_.assign(mesh_.faces.size(), 1);
    alive_faces_ = mesh_.faces.size();
    for (size_t f = 0; f < mesh_.faces.size(); ++f) {
      const Eigen::Vector3i& t = mesh_.faces[f];
      for (int k = 0; k < 3; ++k)
        if (t[k] < 0 || static_cast<size_t>(t[k]) >= nv)
          throw std::invalid_argument("decimateMesh: face " + std::to_string(f) + " has vertex index " +
                                      std::to_string(t[k]) + " of " + std::to_string(nv) + " vertices");
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {  // a repeated index: drop the face
        alive_face_[f] = 0;
        --alive_faces_;
        continue;
      }
      for (int k = 0; k < 3; ++k) faces_of_[t[k]].push_back(static_cast<int>(f));
      const Eigen::Vector3d n = (pos_[t[1]] - pos_[t[0]]).cross(pos_[t[2]] - pos_[t[0]]);
      const double len = n.norm();
      if (len <= 0.0) continue;  // a zero-area face has no plane
      const Eigen::Vector3d u = n / len;
      Quadric q;
      q.addPlane(u, -u.dot(pos_[t[0]]));
      for (int k = 0; k < 3; ++k) quadric_[t[k]] += q;
    }
    // Edges: boundary (one face) and non-manifold (more than two) ones lock their vertices.
    std::vector<std::pair<int, int>> edges;
    edges.reserve(3 * alive_faces_);
    for (size_t f = 0; f < mesh_.faces.size(); ++f) {
      if (!alive_face_[f]) continue;
      const Eigen::Vector3i& t = mesh_.faces[f];
      for (int k = 0; k < 3; ++k) edges.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    }
    std::sort(edges.begin(), edges.end());
    std::vector<std::pair<int, int>> unique;
    unique.reserve(edges.size() / 2 + 1);
    for (size_t i = 0; i < edges.size();) {
      size_t j = i;
      while (j < edges.size() && edges[j] == edges[i]) ++j;
      if (j - i != 2) locked_[edges[i].first] = locked_[edges[i].second] = 1;
      unique.push_back(edges[i]);
      i = j;
    }
    edges.clear();
    edges.shrink_to_fit();
    // A vertex whose faces do not form one closed fan (two cones touching) stays too.
    for (size_t w = 0; w < nv; ++w)
      if (!locked_[w] && !faces_of_[w].empty() && !singleFan(static_cast<int>(w))) locked_[w] = 1;
    for (size_t w = 0; w < nv; ++w) stats_.locked_vertices += locked_[w] && !faces_of_[w].empty();
    for (const auto& e : unique) push(e.first, e.second);
  }

  bool singleFan(int w) const {
    std::vector<std::pair<int, int>> next;  // per face around w: the edge opposite w, in winding order
    for (const int f : faces_of_[w]) {
      const Eigen::Vector3i& t = mesh_.faces[f];
      const int k = t[0] == w ? 0 : (t[1] == w ? 1 : 2);
      next.emplace_back(t[(k + 1) % 3], t[(k + 2) % 3]);
    }
    int at = next[0].first;
    for (size_t steps = 0; steps < next.size(); ++steps) {
      const auto it =
          std::find_if(next.begin(), next.end(), [&](const std::pair<int, int>& e) { return e.first == at; });
      if (it == next.end()) return false;
      at = it->second;
    }
    return at == next[0].first;
  }

  /// Cost of merging v into u, and where the merged vertex goes. A locked vertex stays; two locked
  /// ones are never merged (infinite cost).
  double placement(int u, int v, Eigen::Vector3d* p) const {
    Quadric q = quadric_[u];
    q += quadric_[v];
    if (locked_[u] && locked_[v]) return std::numeric_limits<double>::infinity();
    if (locked_[u] || locked_[v]) {
      *p = locked_[u] ? pos_[u] : pos_[v];
      return q.eval(*p);
    }
    // The quadric's minimum on the edge (the merged vertex stays between the two, where the surface
    // runs; on a flat patch every point of the edge is as good: its middle).
    const Eigen::Vector3d d = pos_[v] - pos_[u];
    const Eigen::Matrix3d A = q.A();
    const double curvature = d.dot(A * d);
    const double t = curvature > 1e-12 * A.trace() * d.squaredNorm()
                         ? std::clamp(-d.dot(A * pos_[u] + q.b()) / curvature, 0.0, 1.0)
                         : 0.5;
    *p = pos_[u] + t * d;
    double best = q.eval(*p);
    for (const Eigen::Vector3d& c : {pos_[u], pos_[v]}) {
      const double e = q.eval(c);
      if (e < best) best = e, *p = c;
    }
    return best;
  }

  void push(int u, int v) {
    if (locked_[v] && !locked_[u]) std::swap(u, v);  // the locked vertex stays: v goes into u
    Eigen::Vector3d p;
    const double cost = placement(u, v, &p);
    if (!std::isfinite(cost) || cost > config_.max_error_m * config_.max_error_m) return;
    uint32_t slot;
    if (!free_.empty()) {
      slot = free_.back();
      free_.pop_back();
      pool_[slot] = Candidate{u, v, version_[u], version_[v]};
    } else {
      slot = static_cast<uint32_t>(pool_.size());
      pool_.push_back(Candidate{u, v, version_[u], version_[v]});
    }
    queue_.push(cost, slot);
  }

  void neighbours(int w, std::vector<int>* out) const {
    out->clear();
    for (const int f : faces_of_[w]) {
      if (!alive_face_[f]) continue;
      for (int k = 0; k < 3; ++k)
        if (mesh_.faces[f][k] != w) out->push_back(mesh_.faces[f][k]);
    }
    std::sort(out->begin(), out->end());
    out->erase(std::unique(out->begin(), out->end()), out->end());
  }

  /// The link condition (the common neighbours of u and v are exactly the opposite corners of the
  /// edge's two faces) and no face around them folds or becomes a sliver.
  bool collapsible(int u, int v, const Eigen::Vector3d& p) {
    // Common neighbours by marks (u's with one stamp, each common one counted once with the next).
    if (stamp_ >= 0xFFFFFFF0u) {
      std::fill(mark_.begin(), mark_.end(), 0u);
      stamp_ = 0;
    }
    const uint32_t mine = ++stamp_, counted = ++stamp_;
    for (const int f : faces_of_[u])
      if (alive_face_[f])
        for (int k = 0; k < 3; ++k) mark_[mesh_.faces[f][k]] = mine;
    size_t common = 0;
    for (const int f : faces_of_[v]) {
      if (!alive_face_[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const int w = mesh_.faces[f][k];
        if (w == u || w == v || mark_[w] != mine) continue;
        mark_[w] = counted;
        ++common;
      }
    }
    int shared = 0;
    for (const int f : faces_of_[u]) {
      if (!alive_face_[f]) continue;
      const Eigen::Vector3i& t = mesh_.faces[f];
      if (t[0] == v || t[1] == v || t[2] == v) ++shared;
    }
    if (shared != 2 || common != 2) return false;
    for (const int w : {u, v}) {
      for (const int f : faces_of_[w]) {
        if (!alive_face_[f]) continue;
        const Eigen::Vector3i& t = mesh_.faces[f];
        if ((t[0] == u || t[1] == u || t[2] == u) && (t[0] == v || t[1] == v || t[2] == v)) continue;
        Eigen::Vector3d before[3], after[3];
        for (int k = 0; k < 3; ++k) {
          before[k] = pos_[t[k]];
          after[k] = t[k] == w ? p : pos_[t[k]];
        }
        const Eigen::Vector3d n0 = (before[1] - before[0]).cross(before[2] - before[0]);
        const Eigen::Vector3d n1 = (after[1] - after[0]).cross(after[2] - after[0]);
        const double l0 = n0.norm(), l1 = n1.norm();
        if (l1 <= 0.0) return false;
        if (l0 > 0.0 && n0.dot(n1) < config_.min_normal_cos * l0 * l1) return false;
        const double q1 = quality(after[0], after[1], after[2]);
        if (q1 < 0.05 && q1 < quality(before[0], before[1], before[2])) return false;
      }
    }
    return true;
  }

  void collapse(int u, int v, const Eigen::Vector3d& p) {
    for (const int f : faces_of_[v]) {
      if (!alive_face_[f]) continue;
      Eigen::Vector3i& t = mesh_.faces[f];
      if (t[0] == u || t[1] == u || t[2] == u) {
        alive_face_[f] = 0;
        --alive_faces_;
        continue;
      }
      for (int k = 0; k < 3; ++k)
        if (t[k] == v) t[k] = u;
      faces_of_[u].push_back(f);
    }
    faces_of_[v].clear();
    faces_of_[v].shrink_to_fit();
    std::vector<int>& fu = faces_of_[u];
    fu.erase(std::remove_if(fu.begin(), fu.end(), [&](int f) { return !alive_face_[f]; }), fu.end());
    pos_[u] = p;
    quadric_[u] += quadric_[v];
    alive_vertex_[v] = 0;
    ++version_[u];
    ++version_[v];
    neighbours(u, &nu_);
    for (const int w : nu_) push(u, w);
  }

  void compact() {
    TriangleMesh out;
    std::vector<int> index(pos_.size(), -1);
    for (size_t f = 0; f < mesh_.faces.size(); ++f)
      if (alive_face_[f])
        for (int k = 0; k < 3; ++k) index[mesh_.faces[f][k]] = 0;
    for (size_t i = 0; i < pos_.size(); ++i) {
      if (index[i] < 0) continue;
      index[i] = static_cast<int>(out.vertices.size());
      out.vertices.push_back(pos_[i].cast<float>());
      origin_.push_back(static_cast<int>(i));
    }
    out.faces.reserve(alive_faces_);
    for (size_t f = 0; f < mesh_.faces.size(); ++f) {
      if (!alive_face_[f]) continue;
      const Eigen::Vector3i& t = mesh_.faces[f];
      out.faces.emplace_back(index[t[0]], index[t[1]], index[t[2]]);
    }
    if (!mesh_.normals.empty()) out.normals = vertexNormalsFromFaces(out);
    mesh_ = std::move(out);
  }

  TriangleMesh& mesh_;
  const DecimateConfig& config_;
  std::vector<char> pinned_;
  std::vector<int> origin_;
  DecimateStats stats_;
  std::vector<Eigen::Vector3d> pos_;
  std::vector<Quadric> quadric_;
  std::vector<std::vector<int>> faces_of_;
  std::vector<char> alive_vertex_, locked_, alive_face_;
  std::vector<uint32_t> version_;
  size_t alive_faces_ = 0;
  BucketQueue queue_{config_.max_error_m};
  std::vector<Candidate> pool_;  ///< candidates by slot
  std::vector<uint32_t> free_;   ///< slots popped, for reuse
  std::vector<int> nu_;
  std::vector<uint32_t> mark_;  ///< per vertex: the stamp of the last collapsible() that saw it
  uint32_t stamp_ = 0;
};

}  // namespace

namespace {

/// The two halves of a large mesh decimated at once on two threads: faces split at the median x
/// of their centroids, the vertices both halves use pinned in both (the seam stays as it was, so
/// the halves meet exactly), then joined.
DecimateStats decimateInHalves(TriangleMesh& mesh, const DecimateConfig& config,
                               const std::vector<char>& pinned_by_caller) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t nv = mesh.vertices.size(), nf = mesh.faces.size();
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.faces[f][k] < 0 || static_cast<size_t>(mesh.faces[f][k]) >= nv)
        throw std::invalid_argument("decimateMesh: face " + std::to_string(f) + " has vertex index " +
                                    std::to_string(mesh.faces[f][k]) + " of " + std::to_string(nv) + " vertices");
  std::vector<float> cx(nf);
  for (size_t f = 0; f < nf; ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    cx[f] = mesh.vertices[t[0]].x() + mesh.vertices[t[1]].x() + mesh.vertices[t[2]].x();
  }
  std::vector<float> sorted = cx;
  std::nth_element(sorted.begin(), sorted.begin() + nf / 2, sorted.end());
  const float cut = sorted[nf / 2];
  sorted = {};
  std::vector<char> side(nf), used(nv, 0);  // used: bit 1 by half 0, bit 2 by half 1
  for (size_t f = 0; f < nf; ++f) {
    side[f] = cx[f] < cut ? 0 : 1;
    for (int k = 0; k < 3; ++k) used[mesh.faces[f][k]] |= side[f] ? 2 : 1;
  }
  TriangleMesh half[2];
  std::vector<int> to_half[2], from_half[2];
  std::vector<char> pinned[2];
  for (int h = 0; h < 2; ++h) {
    to_half[h].assign(nv, -1);
    for (size_t i = 0; i < nv; ++i) {
      if (!(used[i] & (h ? 2 : 1))) continue;
      to_half[h][i] = static_cast<int>(half[h].vertices.size());
      from_half[h].push_back(static_cast<int>(i));
      half[h].vertices.push_back(mesh.vertices[i]);
      if (!mesh.normals.empty()) half[h].normals.push_back(mesh.normals[i]);
      pinned[h].push_back(used[i] == 3 || (i < pinned_by_caller.size() && pinned_by_caller[i]));
    }
    for (size_t f = 0; f < nf; ++f)
      if (side[f] == h) {
        const Eigen::Vector3i& t = mesh.faces[f];
        half[h].faces.emplace_back(to_half[h][t[0]], to_half[h][t[1]], to_half[h][t[2]]);
      }
  }
  TriangleMesh original = std::move(mesh);
  mesh = TriangleMesh();
  DecimateStats part[2];
  std::vector<int> origin[2];
  const auto work = [&](int h) {
    Decimator d(half[h], config, std::move(pinned[h]));
    part[h] = d.run();
    origin[h] = d.origin();
    for (int& o : origin[h]) o = from_half[h][o];
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  // Join: half 0's vertices, then half 1's but the pinned seam vertices half 0 has already.
  std::vector<int> joined(nv, -1);
  for (int h = 0; h < 2; ++h) {
    std::vector<int> index(half[h].vertices.size());
    for (size_t i = 0; i < half[h].vertices.size(); ++i) {
      const int o = origin[h][i];
      if (joined[o] < 0) {
        joined[o] = static_cast<int>(mesh.vertices.size());
        mesh.vertices.push_back(half[h].vertices[i]);
      }
      index[i] = joined[o];
    }
    for (const Eigen::Vector3i& t : half[h].faces) mesh.faces.emplace_back(index[t[0]], index[t[1]], index[t[2]]);
  }
  if (!original.normals.empty()) mesh.normals = vertexNormalsFromFaces(mesh);
  DecimateStats s;
  for (const DecimateStats& p : part) s.add(p);
  // The halves share the seam's vertices: the whole mesh's counts, and the wall time of both threads.
  s.faces_before = nf;
  s.vertices_before = nv;
  s.faces_after = mesh.faces.size();
  s.vertices_after = mesh.vertices.size();
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

}  // namespace

void DecimateStats::add(const DecimateStats& part) {
  faces_before += part.faces_before;
  faces_after += part.faces_after;
  vertices_before += part.vertices_before;
  vertices_after += part.vertices_after;
  collapses += part.collapses;
  refused += part.refused;
  locked_vertices += part.locked_vertices;
  max_error_m = std::max(max_error_m, part.max_error_m);
  seconds += part.seconds;
}

DecimateStats decimateMesh(TriangleMesh& mesh, const DecimateConfig& config, const std::vector<char>& pinned) {
  config.validate();
  if (config.max_error_m <= 0.0 || mesh.faces.empty()) {
    DecimateStats none;
    none.faces_before = none.faces_after = mesh.faces.size();
    none.vertices_before = none.vertices_after = mesh.vertices.size();
    return none;
  }
  if (config.max_faces == 0 && config.threads >= 2 && mesh.faces.size() >= kMinFacesToSplit)
    return decimateInHalves(mesh, config, pinned);
  return Decimator(mesh, config, pinned).run();
}

}  // namespace mesher
}  // namespace scanstop
