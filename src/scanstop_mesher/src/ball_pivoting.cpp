#include "scanstop_mesher/ball_pivoting.h"

#include "scanstop_mesher/mesh_analysis.h"

#include <omp.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

namespace scanstop {
namespace mesher {
namespace {

enum : uint8_t {
  kActive = 0,    // waiting to be pivoted
  kBoundary = 1,  // no valid triangle for this radius
  kRemoved = 2,   // no longer on the front
};

constexpr uint64_t kEmptyKey = std::numeric_limits<uint64_t>::max();
/// A point counts as inside a ball when its squared distance to the centre is below
/// r^2 * (1 - kInsideEps): points on the sphere (co-circular samples) do not block it.
constexpr double kInsideEps = 1e-7;

inline uint64_t edgeKey(int a, int b) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}
inline size_t hashKey(uint64_t k) {
  k *= 0x9E3779B97F4A7C15ull;
  return static_cast<size_t>(k ^ (k >> 31));
}

}  // namespace

BallPivoting::BallPivoting(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals) {
  if (points.size() != normals.size())
    throw std::invalid_argument("BallPivoting: " + std::to_string(points.size()) + " points but " +
                                std::to_string(normals.size()) + " normals");
  if (points.size() >= static_cast<size_t>(std::numeric_limits<int>::max()))
    throw std::invalid_argument("BallPivoting: too many points (" + std::to_string(points.size()) + ")");
  const size_t n = points.size();
  num_points_ = n;
  p_store_.resize(n);
  n_store_.resize(n);
  // Internal order: the usable points by Morton code (1/2^20 of the extent per step), then the others.
  std::vector<uint8_t> ok(n, 0);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    const double len = normals[i].cast<double>().norm();
    ok[i] = points[i].allFinite() && normals[i].allFinite() && len > 1e-6;
    if (!ok[i]) continue;
    lo = lo.cwiseMin(points[i].cast<double>());
    hi = hi.cwiseMax(points[i].cast<double>());
  }
  const double step = std::max((hi - lo).maxCoeff(), 1e-9) / double((1 << 20) - 1);
  std::vector<std::pair<uint64_t, int>> order;
  order.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!ok[i]) continue;
    const Eigen::Vector3d c = ((points[i].cast<double>() - lo) / step).array().floor();
    order.emplace_back(
        mortonCode(static_cast<uint64_t>(c[0]), static_cast<uint64_t>(c[1]), static_cast<uint64_t>(c[2])),
        static_cast<int>(i));
  }
  std::sort(order.begin(), order.end());
  perm_.reserve(n);
  for (const auto& o : order) perm_.push_back(o.second);
  std::vector<std::pair<uint64_t, int>>().swap(order);
  for (size_t i = 0; i < n; ++i)
    if (!ok[i]) perm_.push_back(static_cast<int>(i));
  for (size_t k = 0; k < n; ++k) {
    const size_t i = static_cast<size_t>(perm_[k]);
    if (ok[i]) {
      const Eigen::Vector3d nn = normals[i].cast<double>();
      p_store_[k] = points[i].cast<double>();
      n_store_[k] = nn / nn.norm();
      ++stats_.points;
    } else {
      // Left out of the grid: such a point neither becomes a vertex nor blocks a ball.
      p_store_[k] = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
      n_store_[k] = Eigen::Vector3d::Zero();
    }
  }
  used_store_.assign(n, 0);
  out_head_store_.assign(n, -1);
  front_deg_store_.assign(n, 0);
  p_ = p_store_.data();
  n_ = n_store_.data();
  used_ = used_store_.data();
  out_head_ = out_head_store_.data();
  front_deg_ = front_deg_store_.data();
  // The directed-edge set is allocated by the first pass (run() in slabs sizes its own).
  edges_.reserve(4 * n);
  faces_.reserve(2 * n);
}

BallPivoting::BallPivoting(BallPivoting& parent, int region)
    : num_points_(parent.num_points_),
      p_(parent.p_),
      n_(parent.n_),
      used_(parent.used_),
      out_head_(parent.out_head_),
      front_deg_(parent.front_deg_),
      region_(parent.region_),
      region_id_(region) {
  size_t n = 0;
  for (size_t i = 0; i < num_points_; ++i) n += region_[i] == region;
  stats_.points = n;
  allocDirEdges(n);
  edges_.reserve(4 * n);
  faces_.reserve(2 * n);
}

void BallPivoting::allocDirEdges(size_t points) {
  // About 2 triangles, 6 directed edges and 4 front edges per point on a closed surface; a map
  // (thick noisy walls) uses about half its points: 3 directed edges per point. Grows when half full.
  size_t cap = 1024;
  while (cap < 8 * points) cap *= 2;
  dir_edges_.assign(cap, kEmptyKey);
  dir_edge_count_ = 0;
}

BallPivoting::~BallPivoting() = default;

bool BallPivoting::insertDirEdge(uint64_t key) {
  if (2 * (dir_edge_count_ + 1) > dir_edges_.size()) {
    std::vector<uint64_t> old;
    old.swap(dir_edges_);
    dir_edges_.assign(std::max<size_t>(1024, old.size() * 2), kEmptyKey);
    dir_edge_count_ = 0;
    for (uint64_t k : old)
      if (k != kEmptyKey) insertDirEdge(k);
  }
  const size_t mask = dir_edges_.size() - 1;
  for (size_t h = hashKey(key) & mask;; h = (h + 1) & mask) {
    if (dir_edges_[h] == key) return false;
    if (dir_edges_[h] == kEmptyKey) {
      dir_edges_[h] = key;
      ++dir_edge_count_;
      return true;
    }
  }
}

bool BallPivoting::hasDirEdge(uint64_t key) const {
  if (dir_edges_.empty()) return false;
  const size_t mask = dir_edges_.size() - 1;
  for (size_t h = hashKey(key) & mask;; h = (h + 1) & mask) {
    if (dir_edges_[h] == key) return true;
    if (dir_edges_[h] == kEmptyKey) return false;
  }
}

bool BallPivoting::edgeUsed(int a, int b) const { return hasDirEdge(edgeKey(a, b)); }

bool BallPivoting::ballCenter(int a, int b, int c, Eigen::Vector3d& center, bool check_normals) const {
  const Eigen::Vector3d ab = p_[b] - p_[a];
  const Eigen::Vector3d ac = p_[c] - p_[a];
  const Eigen::Vector3d n = ab.cross(ac);
  // The triangle (a, b, c) faces along n: each corner's normal must agree.
  if (check_normals && !(n.dot(n_[a]) > 0.0 && n.dot(n_[b]) > 0.0 && n.dot(n_[c]) > 0.0)) return false;
  const double n2 = n.squaredNorm();
  const double ab2 = ab.squaredNorm(), ac2 = ac.squaredNorm();
  if (!(n2 > 1e-12 * ab2 * ac2)) return false;  // (nearly) collinear or coincident corners
  const Eigen::Vector3d cc = p_[a] + (ac2 * n.cross(ab) + ab2 * ac.cross(n)) / (2.0 * n2);
  const double h2 = radius_ * radius_ - (cc - p_[a]).squaredNorm();
  if (h2 < 0.0) return false;  // no ball of this radius touches the three points
  center = cc + std::sqrt(h2 / n2) * n;
  return true;
}

bool BallPivoting::ballEmpty(const Eigen::Vector3d& center, const std::vector<uint32_t>& candidates, int a, int b,
                             int c) const {
  const double limit = radius_ * radius_ * (1.0 - kInsideEps);
  for (uint32_t q : candidates) {
    if (static_cast<int>(q) == a || static_cast<int>(q) == b || static_cast<int>(q) == c) continue;
    if ((p_[q] - center).squaredNorm() < limit) return false;
  }
  return true;
}

int BallPivoting::newEdge(int a, int b, int opp, const Eigen::Vector3d& center, int loop) {
  Edge e;
  e.a = a;
  e.b = b;
  e.opp = opp;
  e.next = e.prev = -1;
  e.loop = loop;
  e.center = center;
  e.state = kActive;
  e.next_out = out_head_[a];
  edges_.push_back(e);
  const int id = static_cast<int>(edges_.size()) - 1;
  out_head_[a] = id;
  ++front_deg_[a];
  active_.push_back(id);
  return id;
}

void BallPivoting::removeEdge(int e) {
  Edge& E = edges_[e];
  E.state = kRemoved;
  --front_deg_[E.a];
  if (out_head_[E.a] == e) {
    out_head_[E.a] = E.next_out;
    return;
  }
  for (int x = out_head_[E.a]; x >= 0; x = edges_[x].next_out)
    if (edges_[x].next_out == e) {
      edges_[x].next_out = E.next_out;
      return;
    }
}

int BallPivoting::findFront(int a, int b) const {
  for (int x = out_head_[a]; x >= 0; x = edges_[x].next_out)
    if (edges_[x].b == b) return x;
  return -1;
}

void BallPivoting::addFace(int a, int b, int c) {
  faces_.emplace_back(a, b, c);
  used_[a] = used_[b] = used_[c] = 1;
  insertDirEdge(edgeKey(a, b));
  insertDirEdge(edgeKey(b, c));
  insertDirEdge(edgeKey(c, a));
}

void BallPivoting::addSeed(int a, int b, int c, const Eigen::Vector3d& center) {
  addFace(a, b, c);
  const int loop = static_cast<int>(loop_size_.size());
  loop_size_.push_back(3);
  const int e0 = newEdge(a, b, c, center, loop);
  const int e1 = newEdge(b, c, a, center, loop);
  const int e2 = newEdge(c, a, b, center, loop);
  const int ids[3] = {e0, e1, e2};
  for (int k = 0; k < 3; ++k) {
    Edge& E = edges_[ids[k]];
    E.next = ids[(k + 1) % 3];
    E.prev = ids[(k + 2) % 3];
  }
  ++stats_.seeds;
}

void BallPivoting::relabel(int start, int loop) {
  int e = start;
  do {
    edges_[e].loop = loop;
    e = edges_[e].next;
  } while (e != start);
}

void BallPivoting::glue(int x, int y) {
  // x and y have the same end points and opposite directions; both leave the front.
  Edge& X = edges_[x];
  Edge& Y = edges_[y];
  const int lx = X.loop, ly = Y.loop;
  if (lx == ly) {
    if (X.next == y && Y.next == x) {
      // Case 1: the loop consists of these two edges only: it disappears.
      ++stats_.glue[0];
      loop_size_[lx] = 0;
    } else if (X.next == y || Y.next == x) {
      // Case 2: adjacent in a longer loop: unlink both.
      ++stats_.glue[1];
      const int first = X.next == y ? x : y;
      const int second = first == x ? y : x;
      const int before = edges_[first].prev, after = edges_[second].next;
      edges_[before].next = after;
      edges_[after].prev = before;
      loop_size_[lx] -= 2;
    } else {
      // Case 3: same loop, not adjacent: the loop splits into two.
      ++stats_.glue[2];
      const int xn = X.next, xp = X.prev, yn = Y.next, yp = Y.prev;
      edges_[yp].next = xn;
      edges_[xn].prev = yp;  // loop A: xn ... yp
      edges_[xp].next = yn;
      edges_[yn].prev = xp;  // loop B: yn ... xp
      // Count the smaller part by walking both at once; give it a new loop id.
      int a = xn, b = yn, na = 0, nb = 0;
      for (;;) {
        ++na;
        ++nb;
        a = edges_[a].next;
        b = edges_[b].next;
        if (a == xn || b == yn) break;
      }
      const int total = loop_size_[lx] - 2;
      const int fresh = static_cast<int>(loop_size_.size());
      if (a == xn) {
        loop_size_.push_back(na);
        relabel(xn, fresh);
        loop_size_[lx] = total - na;
      } else {
        loop_size_.push_back(nb);
        relabel(yn, fresh);
        loop_size_[lx] = total - nb;
      }
    }
  } else {
    // Case 4: different loops merge into one; the smaller one takes the larger one's id.
    ++stats_.glue[3];
    const int keep = loop_size_[lx] >= loop_size_[ly] ? lx : ly;
    const int drop = keep == lx ? ly : lx;
    relabel(keep == lx ? y : x, keep);
    const int xn = X.next, xp = X.prev, yn = Y.next, yp = Y.prev;
    edges_[xp].next = yn;
    edges_[yn].prev = xp;
    edges_[yp].next = xn;
    edges_[xn].prev = yp;
    loop_size_[keep] += loop_size_[drop] - 2;
    loop_size_[drop] = 0;
  }
  removeEdge(x);
  removeEdge(y);
}

void BallPivoting::join(int e, int q, const Eigen::Vector3d& center) {
  const Edge E = edges_[e];
  const int i = E.a, j = E.b;
  const int glue_iq = used_[q] ? findFront(q, i) : -1;  // front edge q -> i meets the new i -> q
  const int glue_qj = used_[q] ? findFront(j, q) : -1;  // front edge j -> q meets the new q -> j
  if (used_[q] && glue_iq < 0 && glue_qj < 0) {
    ++stats_.pinches;
    pinched_.push_back(q);
  }

  addFace(i, q, j);
  removeEdge(e);
  const int e1 = newEdge(i, q, j, center, E.loop);
  const int e2 = newEdge(q, j, i, center, E.loop);
  edges_[E.prev].next = e1;
  edges_[e1].prev = E.prev;
  edges_[e1].next = e2;
  edges_[e2].prev = e1;
  edges_[e2].next = E.next;
  edges_[E.next].prev = e2;
  ++loop_size_[E.loop];
  if (glue_iq >= 0) glue(e1, glue_iq);
  if (glue_qj >= 0) glue(e2, glue_qj);
  ++stats_.joins;
}

void BallPivoting::pivotEdge(int e) {
  ++stats_.pivots;
  const Edge E = edges_[e];
  const int i = E.a, j = E.b, k = E.opp;
  const Eigen::Vector3d pi = p_[i], pj = p_[j];
  const Eigen::Vector3d m = 0.5 * (pi + pj);
  const double r2 = radius_ * radius_;
  const Eigen::Vector3d ij = pj - pi;
  const double ij2 = ij.squaredNorm();
  const double half2 = 0.25 * ij2;
  if (half2 >= r2) {
    edges_[e].state = kBoundary;
    return;
  }
  const double rho = std::sqrt(r2 - half2);  // radius of the circle of ball centres around the edge
  const Eigen::Vector3d axis = ij.normalized();
  Eigen::Vector3d u = E.center - m;
  u -= axis * axis.dot(u);

  // Only points within 2 r of both i and j can be the third corner of a ball through i and j or
  // lie inside such a ball: the lens, copied for the candidate and empty-ball loops.
  const double reach2 = 4.0 * r2;
  std::vector<LensPoint>& lens = lens_;
  lens.clear();
  grid_->forEachPointWithin(m, radius_ + rho, [&](uint32_t uq, const Eigen::Vector3d& q) {
    const double di2 = (q - pi).squaredNorm();
    if (di2 > reach2) return;
    const double dj2 = (q - pj).squaredNorm();
    if (dj2 > reach2) return;
    lens.push_back({q, di2, dj2, static_cast<int>(uq)});
  });

  // Triangle (i, q, j) faces along n = (q - i) x (j - i); n . n_i = (q - i) . ((j - i) x n_i).
  const Eigen::Vector3d ti = ij.cross(n_[i]), tj = ij.cross(n_[j]);
  std::vector<Candidate>& candidates = candidates_;
  candidates.clear();
  for (const LensPoint& L : lens) {
    const int q = L.q;
    if (q == i || q == j || q == k || !mine(q)) continue;
    const Eigen::Vector3d iq = L.p - pi;
    if (!(iq.dot(ti) > 0.0) || !(iq.dot(tj) > 0.0)) continue;
    const Eigen::Vector3d n = iq.cross(ij);
    if (!(n.dot(n_[q]) > 0.0)) continue;
    const double n2 = n.squaredNorm();
    if (!(n2 > 1e-12 * L.di2 * ij2)) continue;  // (nearly) collinear or coincident corners
    // Circumradius^2 = |iq|^2 |ij|^2 |jq|^2 / (4 |n|^2): no ball of this radius when above r^2.
    const double h2 = r2 - L.di2 * ij2 * L.dj2 / (4.0 * n2);
    if (h2 < 0.0) continue;
    const Eigen::Vector3d cc = pi + (ij2 * n.cross(iq) + L.di2 * ij.cross(n)) / (2.0 * n2);
    const Eigen::Vector3d c = cc + std::sqrt(h2 / n2) * n;
    const Eigen::Vector3d v = c - m;
    // Rotation about i->j (away from k) from u to v, as a pseudo-angle in [0, 4) that orders like
    // the angle in [0, 2 pi) (no atan2 needed for choosing the smallest).
    const double y = axis.dot(u.cross(v)), x = u.dot(v);
    const double l1 = std::abs(x) + std::abs(y);
    if (!(l1 > 0.0)) continue;
    double angle = y >= 0.0 ? (x >= 0.0 ? y / l1 : 1.0 - x / l1) : (x < 0.0 ? 2.0 - y / l1 : 3.0 + x / l1);
    if (angle > 4.0 - 1e-9) angle = 0.0;  // on the current ball's sphere, within rounding
    candidates.push_back({angle, q, c, (L.p - m).squaredNorm()});
  }
  // In order of pivot angle (then distance to the edge's midpoint): usually the first is taken, so
  // the next one is picked by a linear scan instead of sorting all.
  const double limit = r2 * (1.0 - kInsideEps);
  for (size_t taken = 0; taken < candidates.size(); ++taken) {
    size_t best = taken;
    for (size_t x = taken + 1; x < candidates.size(); ++x) {
      const Candidate& a = candidates[x];
      const Candidate& b = candidates[best];
      if (a.angle < b.angle || (a.angle == b.angle && a.dist2 < b.dist2)) best = x;
    }
    std::swap(candidates[taken], candidates[best]);
    const Candidate& c = candidates[taken];
    bool empty = true;
    for (const LensPoint& L : lens)
      if (L.q != i && L.q != j && L.q != c.q && (L.p - c.center).squaredNorm() < limit) {
        empty = false;
        break;
      }
    if (!empty) continue;
    // The valid triangle with the smallest pivot angle: it must not use a vertex inside the
    // surface, give an edge a third triangle, or run an existing edge in the same direction.
    const int q = c.q;
    if (used_[q] && front_deg_[q] == 0) {
      ++stats_.refused_interior;
      break;
    }
    if (used_[q] && (edgeUsed(i, q) || edgeUsed(q, j))) {
      ++stats_.refused_edge;
      break;
    }
    join(e, q, c.center);
    return;
  }
  edges_[e].state = kBoundary;
}

void BallPivoting::processActive() {
  while (head_ < active_.size()) {
    const int e = active_[head_++];
    if (edges_[e].state == kActive) pivotEdge(e);
  }
  active_.clear();
  head_ = 0;
}

bool BallPivoting::findSeed() {
  // Bernardini et al.: seeds are looked for cell by cell (cells of the 2r grid), trying a few
  // unused points per cell; a cell whose tries failed is not tried again in this pass.
  constexpr int kTriesPerCell = 3;
  const std::vector<uint32_t>& order = grid_->cellOrder();
  const double r2 = radius_ * radius_;
  std::vector<std::pair<double, int>>& near = seed_near_;
  for (; seed_cursor_ < grid_->numCells(); ++seed_cursor_) {
    int tries = 0;
    for (uint32_t k = grid_->cellBegin(seed_cursor_); k < grid_->cellBegin(seed_cursor_ + 1) && tries < kTriesPerCell;
         ++k) {
      const int v = static_cast<int>(order[k]);
      if (!mine(v) || used_[v] || (seam_band_ > 0.0 && !nearCut(v))) continue;
      ++tries;
      grid_->within(p_[v], 2.0 * radius_, scratch_);
      near.clear();
      for (uint32_t q : scratch_) {
        if (static_cast<int>(q) == v || !mine(static_cast<int>(q)) || used_[q]) continue;
        const double d2 = (p_[q] - p_[v]).squaredNorm();
        if (d2 < 4.0 * r2) near.emplace_back(d2, static_cast<int>(q));
      }
      const size_t keep = std::min<size_t>(near.size(), 10);  // pairs among the 10 nearest
      std::partial_sort(near.begin(), near.begin() + keep, near.end());
      for (size_t x = 0; x < keep; ++x)
        for (size_t y = x + 1; y < keep; ++y) {
          int a = near[x].second, b = near[y].second;
          if ((p_[a] - p_[v]).cross(p_[b] - p_[v]).dot(n_[v]) < 0.0) std::swap(a, b);
          Eigen::Vector3d c;
          if (!ballCenter(v, a, b, c, true) || !ballEmpty(c, scratch_, v, a, b)) continue;
          addSeed(v, a, b, c);
          return true;  // the same cell is looked at again next time (it may hold more surface)
        }
    }
  }
  return false;
}

void BallPivoting::pivot(double radius_m) {
  if (!(radius_m > 0.0) || !std::isfinite(radius_m))
    throw std::invalid_argument("BallPivoting: radius must be positive and finite, got " + std::to_string(radius_m));
  if (radius_m < radius_)
    throw std::invalid_argument("BallPivoting: radii must increase (" + std::to_string(radius_m) + " after " +
                                std::to_string(radius_) + ")");
  if (dir_edges_.empty()) allocDirEdges(stats_.points);
  grid_store_ = std::make_unique<SpatialGrid>(p_store_, 2.0 * radius_m);
  grid_ = grid_store_.get();
  runPass(radius_m, false);
}

bool BallPivoting::nearCut(int v) const {
  const double x = p_[v][cut_axis_];
  for (double c : cuts_)
    if (std::abs(x - c) < seam_band_) return true;
  return false;
}

void BallPivoting::runPass(double radius_m, bool seam) {
  const auto t0 = std::chrono::steady_clock::now();
  radius_ = radius_m;
  // Thesis 7.4: the boundary of the surface so far becomes active again for the new radius (in
  // the seam phase only where a seam may change it: near a cut, or made by the seam phase).
  active_.clear();
  head_ = 0;
  for (size_t e = 0; e < edges_.size(); ++e) {
    Edge& E = edges_[e];
    if (E.state == kRemoved) continue;
    if (seam && e < seam_first_edge_ && !nearCut(E.a) && !nearCut(E.b)) continue;
    if (ballCenter(E.a, E.b, E.opp, E.center, false)) {
      E.state = kActive;
      active_.push_back(static_cast<int>(e));
    } else {
      E.state = kBoundary;
    }
  }
  seed_cursor_ = 0;
  do processActive();
  while (findSeed());
  stats_.triangles = faces_.size();
  stats_.triangles_per_radius.push_back(faces_.size());
  stats_.seconds_per_radius.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

int BallPivoting::automaticRegions(size_t points) {
  return static_cast<int>(std::max<size_t>(1, std::min<size_t>(4, points / 500000)));
}

void BallPivoting::run(const std::vector<double>& radii_m, int regions) {
  if (regions < 0) throw std::invalid_argument("BallPivoting: regions must be >= 0, got " + std::to_string(regions));
  double prev = radius_;
  for (double r : radii_m) {
    if (!(r > 0.0) || !std::isfinite(r))
      throw std::invalid_argument("BallPivoting: radius must be positive and finite, got " + std::to_string(r));
    if (r < prev)
      throw std::invalid_argument("BallPivoting: radii must increase (" + std::to_string(r) + " after " +
                                  std::to_string(prev) + ")");
    prev = r;
  }
  if (regions == 0) regions = automaticRegions(stats_.points);
  regions = std::min(regions, 64);
  if (regions <= 1 || radii_m.empty() || !edges_.empty() || !faces_.empty() || stats_.points < 3) {
    for (double r : radii_m) pivot(r);
    return;
  }
  runRegions(radii_m, regions);
}

void BallPivoting::runRegions(const std::vector<double>& radii_m, int regions) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = num_points_;
  // Slabs of equal point counts across the longest axis.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t i = 0; i < n; ++i)
    if (p_[i].allFinite()) {
      lo = lo.cwiseMin(p_[i]);
      hi = hi.cwiseMax(p_[i]);
    }
  (hi - lo).maxCoeff(&cut_axis_);
  std::vector<double> x;
  x.reserve(stats_.points);
  for (size_t i = 0; i < n; ++i)
    if (p_[i].allFinite()) x.push_back(p_[i][cut_axis_]);
  cuts_.clear();
  auto from = x.begin();
  for (int k = 1; k < regions; ++k) {
    const auto nth = x.begin() + static_cast<long>(x.size() * k / regions);
    std::nth_element(from, nth, x.end());
    cuts_.push_back(*nth);
    from = nth;
  }
  std::vector<double>().swap(x);
  region_store_.assign(n, 255);
  for (size_t i = 0; i < n; ++i)
    if (p_[i].allFinite())
      region_store_[i] =
          static_cast<uint8_t>(std::upper_bound(cuts_.begin(), cuts_.end(), p_[i][cut_axis_]) - cuts_.begin());
  region_ = region_store_.data();

  std::vector<std::unique_ptr<BallPivoting>> workers;
  for (int k = 0; k < regions; ++k) workers.emplace_back(new BallPivoting(*this, k));
  std::vector<uint64_t>().swap(dir_edges_);  // rebuilt from the merged faces
  dir_edge_count_ = 0;
  for (double r : radii_m) {
    grid_store_ = std::make_unique<SpatialGrid>(p_store_, 2.0 * r);
    grid_ = grid_store_.get();
    std::exception_ptr error;
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::min(regions, omp_get_max_threads()))
    for (int k = 0; k < regions; ++k) {
      try {
        workers[k]->grid_ = grid_;
        workers[k]->runPass(r, false);
      } catch (...) {
#pragma omp critical
        error = std::current_exception();
      }
    }
    if (error) std::rethrow_exception(error);
  }
  stats_.regions = regions;
  stats_.region_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // One front: the workers' edges, loops and faces appended (their vertices are disjoint).
  const auto t1 = std::chrono::steady_clock::now();
  stats_.triangles_per_radius.assign(radii_m.size(), 0);
  stats_.seconds_per_radius.assign(radii_m.size(), 0.0);
  edges_.clear();
  for (int k = 0; k < regions; ++k) {
    merge(*workers[k]);
    workers[k].reset();
  }
  allocDirEdges(stats_.points);
  for (const auto& f : faces_) {
    insertDirEdge(edgeKey(f[0], f[1]));
    insertDirEdge(edgeKey(f[1], f[2]));
    insertDirEdge(edgeKey(f[2], f[0]));
  }

  // Seams: the same passes on the edges and seeds within 2 r of a cut (their candidates may lie
  // across it), and on what these passes add.
  region_ = nullptr;
  const size_t merged_faces = faces_.size();
  seam_first_edge_ = edges_.size();
  for (size_t k = 0; k < radii_m.size(); ++k) {
    const double r = radii_m[k];
    grid_store_ = std::make_unique<SpatialGrid>(p_store_, 2.0 * r);
    grid_ = grid_store_.get();
    seam_band_ = 2.0 * r;
    runPass(r, true);
    // runPass appended its own entries: fold them into the per-radius sums.
    stats_.triangles_per_radius[k] += faces_.size() - merged_faces;
    stats_.seconds_per_radius[k] += stats_.seconds_per_radius.back();
    stats_.triangles_per_radius.pop_back();
    stats_.seconds_per_radius.pop_back();
  }
  seam_band_ = 0.0;
  std::vector<uint8_t>().swap(region_store_);
  stats_.triangles = faces_.size();
  stats_.seam_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
}

void BallPivoting::merge(BallPivoting& child) {
  // Only the edges still on the front are taken over (most edges were removed on the way): new ids,
  // links and the per-vertex lists of the child's vertices renumbered.
  const int l0 = static_cast<int>(loop_size_.size());
  std::vector<int> id(child.edges_.size(), -1);
  int next_id = static_cast<int>(edges_.size());
  for (size_t e = 0; e < child.edges_.size(); ++e)
    if (child.edges_[e].state != kRemoved) id[e] = next_id++;
  auto map = [&id](int e) { return e >= 0 ? id[e] : -1; };
  for (size_t e = 0; e < child.edges_.size(); ++e) {
    Edge E = child.edges_[e];
    if (E.state == kRemoved) continue;
    E.next = map(E.next);
    E.prev = map(E.prev);
    E.next_out = map(E.next_out);
    E.loop += l0;
    edges_.push_back(E);
  }
  for (size_t v = 0; v < num_points_; ++v)
    if (region_[v] == child.region_id_) out_head_[v] = map(out_head_[v]);
  loop_size_.insert(loop_size_.end(), child.loop_size_.begin(), child.loop_size_.end());
  faces_.insert(faces_.end(), child.faces_.begin(), child.faces_.end());
  pinched_.insert(pinched_.end(), child.pinched_.begin(), child.pinched_.end());
  const BpaStats& c = child.stats_;
  stats_.seeds += c.seeds;
  stats_.pivots += c.pivots;
  stats_.joins += c.joins;
  for (int k = 0; k < 4; ++k) stats_.glue[k] += c.glue[k];
  stats_.refused_interior += c.refused_interior;
  stats_.refused_edge += c.refused_edge;
  stats_.pinches += c.pinches;
  for (size_t k = 0; k < c.triangles_per_radius.size() && k < stats_.triangles_per_radius.size(); ++k) {
    stats_.triangles_per_radius[k] += c.triangles_per_radius[k];
    stats_.seconds_per_radius[k] += c.seconds_per_radius[k];
  }
}

std::vector<Eigen::Vector3i> BallPivoting::faces() const {
  std::vector<Eigen::Vector3i> out;
  out.reserve(faces_.size());
  for (const auto& f : faces_) out.emplace_back(perm_[f[0]], perm_[f[1]], perm_[f[2]]);
  return out;
}

TriangleMesh BallPivoting::mesh() {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3i> faces = faces_;
  // Only a pinch gives a vertex a second fan.
  std::vector<int> pinched = pinched_;
  std::sort(pinched.begin(), pinched.end());
  pinched.erase(std::unique(pinched.begin(), pinched.end()), pinched.end());
  stats_.dropped_triangles = dropPinchedFans(faces, num_points_, pinched);
  stats_.triangles = faces.size();
  TriangleMesh mesh;
  // Vertices in input order (index by input index).
  std::vector<int> index(num_points_, -1);
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) index[perm_[f[k]]] = 0;
  std::vector<int> internal(num_points_, -1);
  for (size_t k = 0; k < num_points_; ++k) internal[perm_[k]] = static_cast<int>(k);
  stats_.used_points = 0;
  for (size_t i = 0; i < num_points_; ++i) {
    if (index[i] < 0) continue;
    index[i] = static_cast<int>(mesh.vertices.size());
    mesh.vertices.push_back(p_[internal[i]].cast<float>());
    mesh.normals.push_back(n_[internal[i]].cast<float>());
    ++stats_.used_points;
  }
  mesh.faces.reserve(faces.size());
  for (const auto& f : faces) mesh.faces.emplace_back(index[perm_[f[0]]], index[perm_[f[1]]], index[perm_[f[2]]]);
  stats_.mesh_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return mesh;
}

std::string BallPivoting::checkFront() const {
  std::vector<int> count(loop_size_.size(), 0);
  for (size_t id = 0; id < edges_.size(); ++id) {
    const Edge& E = edges_[id];
    if (E.state == kRemoved) continue;
    const std::string name =
        "edge " + std::to_string(id) + " (" + std::to_string(E.a) + "->" + std::to_string(E.b) + ")";
    if (E.next < 0 || E.prev < 0 || edges_[E.next].state == kRemoved || edges_[E.prev].state == kRemoved)
      return name + ": linked to a removed edge";
    if (edges_[E.next].prev != static_cast<int>(id) || edges_[E.prev].next != static_cast<int>(id))
      return name + ": next/prev inconsistent";
    if (edges_[E.next].a != E.b) return name + ": next does not start at its end";
    if (edges_[E.next].loop != E.loop) return name + ": next in another loop";
    if (findFront(E.a, E.b) != static_cast<int>(id)) return name + ": not in its vertex's list";
    if (!hasDirEdge(edgeKey(E.a, E.b)) || hasDirEdge(edgeKey(E.b, E.a))) return name + ": not a boundary edge";
    ++count[E.loop];
  }
  for (size_t l = 0; l < loop_size_.size(); ++l)
    if (count[l] != loop_size_[l])
      return "loop " + std::to_string(l) + ": size " + std::to_string(loop_size_[l]) + " but " +
             std::to_string(count[l]) + " edges";
  std::vector<int> deg_in(num_points_, 0);
  for (const Edge& E : edges_)
    if (E.state != kRemoved) ++deg_in[E.b];
  for (size_t v = 0; v < num_points_; ++v) {
    int n = 0;
    for (int x = out_head_[v]; x >= 0; x = edges_[x].next_out) {
      if (edges_[x].state == kRemoved) return "vertex " + std::to_string(v) + ": removed edge in its list";
      ++n;
    }
    if (n != front_deg_[v] || n != deg_in[v])
      return "vertex " + std::to_string(v) + ": " + std::to_string(n) + " edges out in its list, count " +
             std::to_string(front_deg_[v]) + ", " + std::to_string(deg_in[v]) + " in";
  }
  return "";
}

TriangleMesh ballPivot(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals,
                       const std::vector<double>& radii_m, BpaStats* stats) {
  BallPivoting bpa(points, normals);
  bpa.run(radii_m);
  TriangleMesh mesh = bpa.mesh();
  if (stats) *stats = bpa.stats();
  return mesh;
}

}  // namespace mesher
}  // namespace scanstop
