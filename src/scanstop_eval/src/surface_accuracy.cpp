#include "scanstop_eval/surface_accuracy.h"

#include <sys/stat.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <optional>
#include <stdexcept>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_eval/surface_coverage.h"

namespace scanstop {
namespace eval {

namespace {

using Vec3d = Eigen::Vector3d;

double segmentDistance2(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
  const Vec3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).squaredNorm();
}

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

/// Calls f(point, weight) for the k^2 centroids of triangle (a, b, c)'s congruent sub-triangles.
template <class F>
void sampleTriangle(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const Eigen::Vector3f& c, double spacing_m,
                    F&& f) {
  const Eigen::Vector3f ab = b - a, ac = c - a;
  const double area = 0.5 * static_cast<double>(ab.cross(ac).norm());
  if (!(area > 0.0) || !std::isfinite(area)) return;
  const double longest = std::max({ab.norm(), ac.norm(), (c - b).norm()});
  const int k = std::max(1, static_cast<int>(std::ceil(longest / spacing_m)));
  const float w = static_cast<float>(area / (static_cast<double>(k) * k));
  const float inv = 1.0f / static_cast<float>(k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; i + j < k; ++j) {
      f(a + ((i + 1.0f / 3) * inv) * ab + ((j + 1.0f / 3) * inv) * ac, w);                      // upward sub-triangle
      if (i + j + 2 <= k) f(a + ((i + 2.0f / 3) * inv) * ab + ((j + 2.0f / 3) * inv) * ac, w);  // downward
    }
}

}  // namespace

float pointTriangleDistance2(const Eigen::Vector3f& pf, const Eigen::Vector3f& af, const Eigen::Vector3f& bf,
                             const Eigen::Vector3f& cf) {
  const Vec3d p = pf.cast<double>(), a = af.cast<double>(), b = bf.cast<double>(), c = cf.cast<double>();
  const Vec3d ab = b - a, ac = c - a;
  if (ab.cross(ac).squaredNorm() <= 1e-24 * std::max(1.0, ab.squaredNorm() * ac.squaredNorm()))
    return static_cast<float>(
        std::min({segmentDistance2(p, a, b), segmentDistance2(p, a, c), segmentDistance2(p, b, c)}));
  // The region of the triangle's plane that p projects into: a corner, an edge or the inside.
  const Vec3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return static_cast<float>(ap.squaredNorm());
  const Vec3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return static_cast<float>(bp.squaredNorm());
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return static_cast<float>((a + (d1 / (d1 - d3)) * ab - p).squaredNorm());
  const Vec3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return static_cast<float>(cp.squaredNorm());
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return static_cast<float>((a + (d2 / (d2 - d6)) * ac - p).squaredNorm());
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return static_cast<float>((b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b) - p).squaredNorm());
  const double inv = 1.0 / (va + vb + vc);
  return static_cast<float>((a + ab * (vb * inv) + ac * (vc * inv) - p).squaredNorm());
}

WorldSurfaceDistance::WorldSurfaceDistance(const TriangleMesh& world, double cell_m, double max_cells) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity()), hi = -lo;
  for (const Eigen::Vector3i& f : world.faces) {
    for (int k = 0; k < 3; ++k)
      if (f[k] < 0 || static_cast<size_t>(f[k]) >= world.vertices.size())
        throw std::invalid_argument("world mesh: face vertex index " + std::to_string(f[k]) + " out of range");
    const Eigen::Vector3f &a = world.vertices[f[0]], &b = world.vertices[f[1]], &c = world.vertices[f[2]];
    if (!a.allFinite() || !b.allFinite() || !c.allFinite()) continue;
    a_.push_back(a);
    b_.push_back(b);
    c_.push_back(c);
    lo = lo.cwiseMin(a).cwiseMin(b).cwiseMin(c);
    hi = hi.cwiseMax(a).cwiseMax(b).cwiseMax(c);
  }
  if (a_.empty()) throw std::invalid_argument("world mesh: no finite triangles");
  double cell = cell_m > 0 ? cell_m : 0.1;
  const Eigen::Vector3d extent = (hi - lo).cast<double>();
  const auto count = [&](double s) { return (extent.x() / s + 3) * (extent.y() / s + 3) * (extent.z() / s + 3); };
  while (count(cell) > max_cells) cell *= 1.25;
  cell_ = static_cast<float>(cell);
  origin_ = lo - Eigen::Vector3f::Constant(cell_);
  for (int a = 0; a < 3; ++a) dims_[a] = static_cast<int>(std::ceil(extent[a] / cell)) + 3;
  // Every cube lists the triangles passing within its circumsphere, so the triangle nearest to any
  // point is listed in the cube holding its nearest point.
  const float reach = 0.5f * std::sqrt(3.0f) * cell_ * 1.001f;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;  // (cube, triangle)
  for (uint32_t t = 0; t < a_.size(); ++t) {
    const Eigen::Vector3f tlo = a_[t].cwiseMin(b_[t]).cwiseMin(c_[t]), thi = a_[t].cwiseMax(b_[t]).cwiseMax(c_[t]);
    int l[3], h[3];
    for (int a = 0; a < 3; ++a) {
      l[a] = std::max(0, static_cast<int>(std::floor((tlo[a] - reach - origin_[a]) / cell_)));
      h[a] = std::min(dims_[a] - 1, static_cast<int>(std::floor((thi[a] + reach - origin_[a]) / cell_)));
    }
    for (int z = l[2]; z <= h[2]; ++z)
      for (int y = l[1]; y <= h[1]; ++y)
        for (int x = l[0]; x <= h[0]; ++x) {
          const Eigen::Vector3f centre = origin_ + cell_ * Eigen::Vector3f(x + 0.5f, y + 0.5f, z + 0.5f);
          if (tri2(centre, t) <= reach * reach)
            pairs.emplace_back(static_cast<uint32_t>((static_cast<size_t>(z) * dims_[1] + y) * dims_[0] + x), t);
        }
  }
  std::sort(pairs.begin(), pairs.end());
  const size_t cubes = static_cast<size_t>(dims_[0]) * dims_[1] * dims_[2];
  start_.assign(cubes + 1, 0);
  ids_.reserve(pairs.size());
  for (const auto& [cube, t] : pairs) {
    ++start_[cube + 1];
    ids_.push_back(t);
  }
  for (size_t i = 0; i < cubes; ++i) start_[i + 1] += start_[i];
}

float WorldSurfaceDistance::bruteForce2(const Eigen::Vector3f& p) const {
  float best = std::numeric_limits<float>::infinity();
  for (uint32_t t = 0; t < a_.size(); ++t) best = std::min(best, tri2(p, t));
  return best;
}

float WorldSurfaceDistance::distance(const Eigen::Vector3f& p) const {
  if (!p.allFinite()) return std::numeric_limits<float>::infinity();
  int c[3];
  for (int a = 0; a < 3; ++a) {
    const float f = std::floor((p[a] - origin_[a]) / cell_);
    if (f < 0 || f >= dims_[a]) return std::sqrt(bruteForce2(p));  // outside the grid: far from everything
    c[a] = static_cast<int>(f);
  }
  float best2 = std::numeric_limits<float>::infinity();
  constexpr int kMaxRing = 3;  // beyond: a point far from every surface, searched by brute force
  for (int r = 0; r <= kMaxRing; ++r) {
    int l[3], h[3];
    bool clipped_all = true;
    for (int a = 0; a < 3; ++a) {
      l[a] = std::max(0, c[a] - r);
      h[a] = std::min(dims_[a] - 1, c[a] + r);
      if (c[a] - r > 0 || c[a] + r < dims_[a] - 1) clipped_all = false;
    }
    for (int z = l[2]; z <= h[2]; ++z)
      for (int y = l[1]; y <= h[1]; ++y)
        for (int x = l[0]; x <= h[0]; ++x) {
          if (std::max({std::abs(x - c[0]), std::abs(y - c[1]), std::abs(z - c[2])}) != r) continue;
          const size_t cube = (static_cast<size_t>(z) * dims_[1] + y) * dims_[0] + x;
          for (uint32_t i = start_[cube]; i < start_[cube + 1]; ++i) best2 = std::min(best2, tri2(p, ids_[i]));
        }
    if (clipped_all) return std::sqrt(best2);  // the whole grid searched
    // Every cube not yet searched lies outside the block [c - r, c + r]: at least this far from p.
    float bound = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (c[a] - r > 0) bound = std::min(bound, p[a] - (origin_[a] + cell_ * (c[a] - r)));
      if (c[a] + r < dims_[a] - 1) bound = std::min(bound, origin_[a] + cell_ * (c[a] + r + 1) - p[a]);
    }
    if (best2 <= bound * bound) return std::sqrt(best2);
  }
  return std::sqrt(bruteForce2(p));
}

SurfaceSamples sampleMeshSurface(const TriangleMesh& mesh, double spacing_m) {
  if (!(spacing_m > 0.0)) throw std::invalid_argument("sample spacing " + std::to_string(spacing_m) + " m must be > 0");
  SurfaceSamples out;
  for (const Eigen::Vector3i& f : mesh.faces) {
    for (int k = 0; k < 3; ++k)
      if (f[k] < 0 || static_cast<size_t>(f[k]) >= mesh.vertices.size())
        throw std::invalid_argument("mesh: face vertex index " + std::to_string(f[k]) + " out of range");
    sampleTriangle(mesh.vertices[f[0]], mesh.vertices[f[1]], mesh.vertices[f[2]], spacing_m,
                   [&](const Eigen::Vector3f& p, float w) {
                     out.points.push_back(p);
                     out.weights.push_back(w);
                     out.area_m2 += w;
                   });
  }
  return out;
}

DistanceStats distanceStats(std::vector<std::pair<float, float>> dw, const std::vector<double>& within_m) {
  dw.erase(std::remove_if(dw.begin(), dw.end(),
                          [](const std::pair<float, float>& e) { return !std::isfinite(e.first) || !(e.second > 0); }),
           dw.end());
  DistanceStats s;
  s.within_m = within_m;
  s.share.assign(within_m.size(), 0.0);
  s.count = dw.size();
  if (dw.empty()) return s;
  std::sort(dw.begin(), dw.end());
  double total = 0, sum = 0, sum2 = 0;
  for (const auto& [d, w] : dw) {
    total += w;
    sum += static_cast<double>(w) * d;
    sum2 += static_cast<double>(w) * d * d;
  }
  s.mean_m = sum / total;
  s.rms_m = std::sqrt(sum2 / total);
  s.max_m = dw.back().first;
  bool have_median = false, have_p95 = false;
  std::vector<bool> done(within_m.size(), false);
  double cumulative = 0;
  for (size_t i = 0; i < dw.size(); ++i) {
    cumulative += dw[i].second;
    if (!have_median && cumulative >= 0.5 * total) {
      s.median_m = dw[i].first;
      have_median = true;
    }
    if (!have_p95 && cumulative >= 0.95 * total) {
      s.p95_m = dw[i].first;
      have_p95 = true;
    }
    const bool last_of_value = i + 1 == dw.size() || dw[i + 1].first != dw[i].first;
    for (size_t k = 0; k < within_m.size(); ++k)
      if (last_of_value && dw[i].first <= static_cast<float>(within_m[k])) s.share[k] = cumulative / total;
  }
  if (!have_median) s.median_m = s.max_m;  // rounding of the cumulative sum
  if (!have_p95) s.p95_m = s.max_m;
  return s;
}

DistanceStats distanceStats(const std::vector<float>& distances, const std::vector<double>& within_m) {
  std::vector<std::pair<float, float>> dw;
  dw.reserve(distances.size());
  for (const float d : distances) dw.emplace_back(d, 1.0f);
  return distanceStats(std::move(dw), within_m);
}

const char* kindName(AccuracyInput::Kind kind) {
  switch (kind) {
    case AccuracyInput::Kind::Mesh:
      return "mesh";
    case AccuracyInput::Kind::Cloud:
      return "cloud";
    case AccuracyInput::Kind::MapDirectory:
      return "map";
  }
  return "?";
}

AccuracyInput loadAccuracyInput(const std::string& path, bool skip_bad) {
  AccuracyInput in;
  in.path = path;
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw IoError(path, "does not exist (a mesh, a point cloud or a map directory)");
  if (S_ISDIR(st.st_mode)) {
    struct stat poses;
    if (::stat((path + "/poses.csv").c_str(), &poses) != 0)
      throw IoError(path, "a directory without poses.csv: not a map directory");
    in.kind = AccuracyInput::Kind::MapDirectory;
    const MapDirectory map = openMapForTool(path, skip_bad, [&in](const std::string& p) { in.problems.push_back(p); });
    for (size_t i = 0; i < map.size(); ++i) {
      PointCloud cloud;
      try {
        cloud = map.loadScanInMap(i);
      } catch (const std::exception& e) {
        if (!skip_bad) throw;
        in.problems.push_back("skipped: scan " + std::to_string(map.scans()[i].index) + ": " + e.what());
        continue;
      }
      for (const Eigen::Vector3f& p : cloud.points)
        if (p.allFinite()) in.points.push_back(p);
      ++in.scans;
    }
    if (in.scans == 0) throw IoError(path, "the map directory holds no loadable scan");
  } else {
    const std::string ext = lowerExtension(path);
    if (ext == ".stl") {
      in.kind = AccuracyInput::Kind::Mesh;
      in.mesh = readStl(path);
    } else if (ext == ".ply") {
      TriangleMesh m = readPly(path);
      const std::string far = coordinateProblem(m.vertices, "vertex");
      if (!far.empty()) throw IoError(path, far);
      if (m.faces.empty()) {
        in.kind = AccuracyInput::Kind::Cloud;
        for (const Eigen::Vector3f& p : m.vertices)
          if (p.allFinite()) in.points.push_back(p);
      } else {
        in.kind = AccuracyInput::Kind::Mesh;
        in.mesh = std::move(m);
      }
    } else if (ext == ".pcd" || ext == ".xyz" || ext == ".txt") {
      in.kind = AccuracyInput::Kind::Cloud;
      for (const Eigen::Vector3f& p : readCloud(path).points)
        if (p.allFinite()) in.points.push_back(p);
    } else {
      throw IoError(path, "unknown extension '" + ext +
                              "' (a mesh .ply/.stl, a point cloud .ply/.pcd/.xyz/.txt, or a map directory)");
    }
    if (in.kind == AccuracyInput::Kind::Mesh && in.mesh.faces.empty()) throw IoError(path, "the mesh has no triangles");
    if (in.kind == AccuracyInput::Kind::Cloud && in.points.empty()) throw IoError(path, "no finite points");
  }
  return in;
}

SurfaceAccuracy measureSurfaceAccuracy(const WorldSurfaceDistance& world, const VisibleSurface* visible,
                                       const AccuracyInput& input, const Pose2D& world_T_map,
                                       const AccuracyConfig& config) {
  if (!(config.sample_spacing_m > 0.0) || !std::isfinite(config.sample_spacing_m))
    throw ConfigError("sample spacing = " + std::to_string(config.sample_spacing_m) + " m must be finite and > 0");
  std::optional<SurfaceCoverage> coverage;
  if (visible) coverage.emplace(*visible, config.tolerance_m);
  const Eigen::Isometry3f T = world_T_map.toIsometry3f();
  SurfaceAccuracy out;
  double coverage_s = 0.0;
  const auto t0 = std::chrono::steady_clock::now();

  // Distances of a batch of world points (parallel), then its coverage (serial).
  const auto measure = [&](const std::vector<Eigen::Vector3f>& pts, std::vector<float>& d, bool covers) {
    d.resize(pts.size());
    const long n = static_cast<long>(pts.size());
#pragma omp parallel for schedule(dynamic, 4096)
    for (long i = 0; i < n; ++i) d[static_cast<size_t>(i)] = world.distance(pts[static_cast<size_t>(i)]);
    if (coverage && covers) {
      const auto tc = std::chrono::steady_clock::now();
      coverage->add(pts);
      coverage_s += seconds(tc);
    }
  };

  std::vector<Eigen::Vector3f> batch;
  std::vector<float> d;
  if (input.kind == AccuracyInput::Kind::Mesh) {
    const TriangleMesh& mesh = input.mesh;
    out.triangles = mesh.faces.size();
    out.vertices = mesh.vertices.size();
    std::vector<float> vertex_d;
    batch.reserve(mesh.vertices.size());
    for (const Eigen::Vector3f& v : mesh.vertices) batch.push_back(T * v);
    measure(batch, vertex_d, false);  // coverage: the faces' samples
    out.vertex_distance = distanceStats(vertex_d, config.within_m);
    std::vector<float>().swap(vertex_d);

    std::vector<std::pair<float, float>> sample_dw;
    std::vector<float> weights;
    constexpr size_t kBatch = 1 << 18;
    batch.clear();
    const auto flush = [&]() {
      measure(batch, d, true);
      for (size_t i = 0; i < batch.size(); ++i) sample_dw.emplace_back(d[i], weights[i]);
      batch.clear();
      weights.clear();
    };
    for (const Eigen::Vector3i& f : mesh.faces) {
      for (int k = 0; k < 3; ++k)
        if (f[k] < 0 || static_cast<size_t>(f[k]) >= mesh.vertices.size())
          throw IoError(input.path, "face vertex index " + std::to_string(f[k]) + " out of range");
      sampleTriangle(T * mesh.vertices[f[0]], T * mesh.vertices[f[1]], T * mesh.vertices[f[2]], config.sample_spacing_m,
                     [&](const Eigen::Vector3f& p, float w) {
                       batch.push_back(p);
                       weights.push_back(w);
                       out.area_m2 += w;
                     });
      if (batch.size() >= kBatch) flush();
    }
    flush();
    out.samples = sample_dw.size();
    out.surface_distance = distanceStats(std::move(sample_dw), config.within_m);
  } else {
    out.points = input.points.size();
    std::vector<float> all;
    all.reserve(input.points.size());
    constexpr size_t kBatch = 1 << 18;
    for (size_t begin = 0; begin < input.points.size(); begin += kBatch) {
      const size_t end = std::min(input.points.size(), begin + kBatch);
      batch.clear();
      for (size_t i = begin; i < end; ++i) batch.push_back(T * input.points[i]);
      measure(batch, d, true);
      all.insert(all.end(), d.begin(), d.end());
    }
    out.vertex_distance = distanceStats(all, config.within_m);
    out.surface_distance = out.vertex_distance;
  }
  if (coverage) {
    out.visible = coverage->visible();
    out.covered = coverage->covered();
    out.coverage = coverage->share();
  }
  out.coverage_s = coverage_s;
  out.distance_s = seconds(t0) - coverage_s;
  return out;
}

}  // namespace eval
}  // namespace scanstop
