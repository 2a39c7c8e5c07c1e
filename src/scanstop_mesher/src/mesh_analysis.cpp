#include "scanstop_mesher/mesh_analysis.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace scanstop {
namespace mesher {
namespace {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

inline uint64_t undirectedKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
}

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace

namespace {

/// Groups the faces around each vertex into fans (edge-connected around the vertex). Calls
/// visit(v, local fan label per incident face, incident face ids, fan count) for every vertex
/// with more than one fan.
template <typename F>
void forEachPinchedVertex(const std::vector<Eigen::Vector3i>& faces, size_t nv, F&& visit) {
  std::vector<int> start(nv + 1, 0);
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) ++start[f[k] + 1];
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<int> incident(start.back());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (size_t fi = 0; fi < faces.size(); ++fi)
    for (int k = 0; k < 3; ++k) incident[fill[faces[fi][k]]++] = static_cast<int>(fi);
  std::vector<std::pair<int, int>> spokes;
  std::vector<int> parent;
  std::vector<int> local;
  for (size_t v = 0; v < nv; ++v) {
    const int n = start[v + 1] - start[v];
    if (n <= 1) continue;
    spokes.clear();
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
    for (int l = 0; l < n; ++l) {
      const auto& f = faces[incident[start[v] + l]];
      for (int k = 0; k < 3; ++k)
        if (f[k] != static_cast<int>(v)) spokes.emplace_back(f[k], l);
    }
    std::sort(spokes.begin(), spokes.end());
    auto find = [&parent](int x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (size_t s = 1; s < spokes.size(); ++s)
      if (spokes[s].first == spokes[s - 1].first) parent[find(spokes[s].second)] = find(spokes[s - 1].second);
    int fans = 0;
    for (int l = 0; l < n; ++l) fans += find(l) == l;
    if (fans <= 1) continue;
    local.resize(n);
    for (int l = 0; l < n; ++l) local[l] = find(l);
    visit(v, local, &incident[start[v]], n);
  }
}

}  // namespace

MeshTopology analyzeTopology(const TriangleMesh& mesh) {
  MeshTopology t;
  const size_t nv = mesh.vertices.size();
  std::vector<Eigen::Vector3i> faces;
  for (const auto& f : mesh.faces) {
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      ++t.degenerate_faces;
      continue;
    }
    faces.push_back(f);
  }
  t.faces = faces.size();
  // Edges: the faces' sides sorted by undirected key (a hash map of millions of edges is several
  // times slower); forward = the face runs the edge min -> max.
  struct Side {
    uint64_t key;
    int face;
    int forward;
  };
  std::vector<Side> sides;
  sides.reserve(3 * faces.size());
  std::vector<uint8_t> used(nv, 0);
  for (size_t fi = 0; fi < faces.size(); ++fi)
    for (int k = 0; k < 3; ++k) {
      const int a = faces[fi][k], b = faces[fi][(k + 1) % 3];
      used[a] = 1;
      sides.push_back({undirectedKey(a, b), static_cast<int>(fi), a < b ? 1 : 0});
    }
  std::sort(sides.begin(), sides.end(), [](const Side& x, const Side& y) { return x.key < y.key; });
  for (uint8_t u : used) t.vertices += u;
  UnionFind comp(faces.size());
  std::vector<std::pair<int, int>> boundary;  // boundary edge a -> b (as run by its face)
  for (size_t s = 0; s < sides.size();) {
    size_t e = s;
    int forward = 0;
    while (e < sides.size() && sides[e].key == sides[s].key) {
      forward += sides[e].forward;
      if (e > s) comp.unite(sides[s].face, sides[e].face);
      ++e;
    }
    const size_t n = e - s;
    ++t.edges;
    if (n == 1) {
      ++t.boundary_edges;
      const int lo = static_cast<int>(sides[s].key >> 32), hi = static_cast<int>(sides[s].key & 0xffffffffu);
      boundary.emplace_back(forward ? lo : hi, forward ? hi : lo);
    }
    if (n > 2) ++t.nonmanifold_edges;
    if (n == 2 && forward != 1) ++t.inconsistent_edges;
    s = e;
  }
  std::vector<Side>().swap(sides);
  for (size_t fi = 0; fi < faces.size(); ++fi)
    if (comp.find(static_cast<int>(fi)) == static_cast<int>(fi)) ++t.components;

  forEachPinchedVertex(faces, nv, [&t](size_t, const std::vector<int>&, const int*, int) { ++t.nonmanifold_vertices; });

  // Boundary loops (meaningful for manifold meshes): follow boundary edges a -> b.
  if (t.nonmanifold_edges == 0 && t.nonmanifold_vertices == 0) {
    std::vector<int> next(nv, -1);
    for (const auto& ab : boundary) next[ab.first] = ab.second;
    std::vector<uint8_t> seen(nv, 0);
    for (const auto& ab : boundary) {
      if (seen[ab.first]) continue;
      ++t.boundary_loops;
      int v = ab.first;
      while (v >= 0 && !seen[v]) {
        seen[v] = 1;
        v = next[v];
      }
    }
  }
  return t;
}

size_t dropPinchedFans(std::vector<Eigen::Vector3i>& faces, size_t num_vertices) {
  size_t removed = 0;
  for (;;) {
    std::vector<uint8_t> drop(faces.size(), 0);
    bool any = false;
    forEachPinchedVertex(faces, num_vertices, [&](size_t, const std::vector<int>& label, const int* inc, int n) {
      std::vector<int> size(n, 0);
      for (int l = 0; l < n; ++l) ++size[label[l]];
      const int keep = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
      for (int l = 0; l < n; ++l)
        if (label[l] != keep) drop[inc[l]] = 1;
      any = true;
    });
    if (!any) return removed;
    size_t w = 0;
    for (size_t fi = 0; fi < faces.size(); ++fi)
      if (!drop[fi]) faces[w++] = faces[fi];
    removed += faces.size() - w;
    faces.resize(w);
  }
}

size_t dropPinchedFans(std::vector<Eigen::Vector3i>& faces, size_t num_vertices, std::vector<int> candidates) {
  size_t removed = 0;
  std::vector<uint8_t> flag(num_vertices, 0);
  std::vector<std::pair<int, int>> incident;  // (vertex, face)
  std::vector<std::pair<int, int>> spokes;
  std::vector<int> parent, size;
  while (!candidates.empty()) {
    for (int v : candidates) flag[v] = 1;
    incident.clear();
    for (size_t fi = 0; fi < faces.size(); ++fi)
      for (int k = 0; k < 3; ++k)
        if (flag[faces[fi][k]]) incident.emplace_back(faces[fi][k], static_cast<int>(fi));
    for (int v : candidates) flag[v] = 0;
    std::sort(incident.begin(), incident.end());
    std::vector<uint8_t> drop(faces.size(), 0);
    std::vector<int> next;
    for (size_t s = 0; s < incident.size();) {
      size_t e = s;
      while (e < incident.size() && incident[e].first == incident[s].first) ++e;
      const int v = incident[s].first, n = static_cast<int>(e - s);
      spokes.clear();
      parent.resize(n);
      std::iota(parent.begin(), parent.end(), 0);
      for (int l = 0; l < n; ++l) {
        const auto& f = faces[incident[s + l].second];
        for (int k = 0; k < 3; ++k)
          if (f[k] != v) spokes.emplace_back(f[k], l);
      }
      std::sort(spokes.begin(), spokes.end());
      auto find = [&parent](int x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
      };
      for (size_t t = 1; t < spokes.size(); ++t)
        if (spokes[t].first == spokes[t - 1].first) parent[find(spokes[t].second)] = find(spokes[t - 1].second);
      size.assign(n, 0);
      for (int l = 0; l < n; ++l) ++size[find(l)];
      const int keep = static_cast<int>(std::max_element(size.begin(), size.end()) - size.begin());
      for (int l = 0; l < n; ++l)
        if (find(l) != keep && !drop[incident[s + l].second]) {
          drop[incident[s + l].second] = 1;
          for (int k = 0; k < 3; ++k) next.push_back(faces[incident[s + l].second][k]);
        }
      s = e;
    }
    size_t w = 0;
    for (size_t fi = 0; fi < faces.size(); ++fi)
      if (!drop[fi]) faces[w++] = faces[fi];
    removed += faces.size() - w;
    faces.resize(w);
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    candidates.swap(next);
  }
  return removed;
}

SurfaceDistance distanceToSurface(const std::vector<Eigen::Vector3f>& samples, const TriangleMesh& reference) {
  SurfaceDistance result;
  if (samples.empty() || reference.faces.empty()) return result;
  // Grid of reference triangles by bounding box; cell = 2 x mean edge length.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double edge_sum = 0.0;
  for (const auto& f : reference.faces) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = reference.vertices[f[k]].cast<double>();
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    edge_sum += (reference.vertices[f[1]] - reference.vertices[f[0]]).norm();
  }
  double cell = std::max(2.0 * edge_sum / reference.faces.size(), 1e-9);
  Eigen::Vector3i dims;
  for (;;) {
    for (int d = 0; d < 3; ++d) dims[d] = static_cast<int>((hi[d] - lo[d]) / cell) + 1;
    if (static_cast<double>(dims[0]) * dims[1] * dims[2] <= 8.0 * reference.faces.size() + 64) break;
    cell *= 1.5;
  }
  auto cellOf = [&](const Eigen::Vector3d& p, int d) {
    return std::min(dims[d] - 1, std::max(0, static_cast<int>(std::floor((p[d] - lo[d]) / cell))));
  };
  const size_t ncells = static_cast<size_t>(dims[0]) * dims[1] * dims[2];
  std::vector<std::vector<int>> cells(ncells);
  for (size_t fi = 0; fi < reference.faces.size(); ++fi) {
    const auto& f = reference.faces[fi];
    Eigen::Vector3d a = reference.vertices[f[0]].cast<double>(), b = a;
    for (int k = 1; k < 3; ++k) {
      a = a.cwiseMin(reference.vertices[f[k]].cast<double>());
      b = b.cwiseMax(reference.vertices[f[k]].cast<double>());
    }
    for (int z = cellOf(a, 2); z <= cellOf(b, 2); ++z)
      for (int y = cellOf(a, 1); y <= cellOf(b, 1); ++y)
        for (int x = cellOf(a, 0); x <= cellOf(b, 0); ++x)
          cells[(static_cast<size_t>(z) * dims[1] + y) * dims[0] + x].push_back(static_cast<int>(fi));
  }
  double sum = 0.0;
  for (const auto& sf : samples) {
    const Eigen::Vector3d p = sf.cast<double>();
    double best = std::numeric_limits<double>::infinity();
    // Grow the searched shell until the best distance is inside the searched region.
    for (int ring = 1;; ++ring) {
      const int cx = cellOf(p, 0), cy = cellOf(p, 1), cz = cellOf(p, 2);
      for (int z = std::max(0, cz - ring); z <= std::min(dims[2] - 1, cz + ring); ++z)
        for (int y = std::max(0, cy - ring); y <= std::min(dims[1] - 1, cy + ring); ++y)
          for (int x = std::max(0, cx - ring); x <= std::min(dims[0] - 1, cx + ring); ++x) {
            const bool shell =
                ring == 1 || std::abs(z - cz) == ring || std::abs(y - cy) == ring || std::abs(x - cx) == ring;
            if (!shell) continue;
            for (int fi : cells[(static_cast<size_t>(z) * dims[1] + y) * dims[0] + x]) {
              const auto& f = reference.faces[fi];
              const Eigen::Vector3d q =
                  closestOnTriangle(p, reference.vertices[f[0]].cast<double>(), reference.vertices[f[1]].cast<double>(),
                                    reference.vertices[f[2]].cast<double>());
              best = std::min(best, (q - p).squaredNorm());
            }
          }
      const bool covers_all = ring >= std::max(dims[0], std::max(dims[1], dims[2]));
      if (std::sqrt(best) <= ring * cell || covers_all) break;
    }
    const double d = std::sqrt(best);
    sum += d;
    result.max_m = std::max(result.max_m, d);
  }
  result.samples = samples.size();
  result.mean_m = sum / samples.size();
  return result;
}

std::vector<Eigen::Vector3f> sampleFaces(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(mesh.faces.size() * 4);
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3f c = (mesh.vertices[f[0]] + mesh.vertices[f[1]] + mesh.vertices[f[2]]) / 3.0f;
    out.push_back(c);
    for (int k = 0; k < 3; ++k) out.push_back(0.5f * (c + mesh.vertices[f[k]]));
  }
  return out;
}

std::vector<Eigen::Vector3f> vertexNormalsFromFaces(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> n(mesh.vertices.size(), Eigen::Vector3f::Zero());
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3f a =
        (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
    for (int k = 0; k < 3; ++k) n[f[k]] += a;
  }
  for (auto& v : n)
    if (v.norm() > 0) v.normalize();
  return n;
}

}  // namespace mesher
}  // namespace scanstop
