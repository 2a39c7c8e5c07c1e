#include "scanstop_mesher/mesher.h"

#include <sys/stat.h>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/spatial_grid.h"

namespace scanstop {
namespace mesher {
namespace {

double elapsed(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<Eigen::Vector3d> toDouble(const std::vector<Eigen::Vector3f>& pts) {
  std::vector<Eigen::Vector3d> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) out[i] = pts[i].cast<double>();
  return out;
}

}  // namespace

std::unique_ptr<const MapDirectory> openMapDirectory(const std::string& dir, std::vector<std::string>* skipped) {
  // Reading must not create anything (MapDirectory would create a missing directory).
  struct stat st;
  if (::stat((dir + "/poses.csv").c_str(), &st) != 0)
    throw IoError(dir + "/poses.csv", "does not exist (no scan in the map yet)");
  auto map = std::make_unique<const MapDirectory>(dir);
  for (const MapProblem& p : map->problems()) {
    if (!skipped) throw IoError(p.path, p.withoutSkipNote());
    skipped->push_back(p.message());
  }
  if (map->size() == 0) throw IoError(map->posesPath(), "the map has no scans");
  return map;
}

ScanPoints loadMapDirectory(const std::string& dir, std::vector<std::string>* skipped) {
  const std::unique_ptr<const MapDirectory> opened = openMapDirectory(dir, skipped);
  const MapDirectory& map = *opened;
  ScanPoints out;
  size_t loaded = 0;
  for (size_t s = 0; s < map.size(); ++s) {
    const MapScanInfo& info = map.scans()[s];
    const Eigen::Isometry3f T_map_base = info.map_pose.toIsometry3f();
    // The origin is kept for a skipped scan too: views index origins by scan.
    out.origins.push_back(T_map_base * info.sensor_origin.cast<float>());
    PointCloud scan;
    try {
      scan = map.loadScan(s);
    } catch (const std::exception& e) {
      if (!skipped) throw;
      skipped->push_back("scan " + std::to_string(info.index) + " skipped: " + e.what());
      continue;
    }
    ++loaded;
    for (const auto& p : scan.points) {
      if (!p.allFinite()) continue;
      out.points.push_back(T_map_base * p);
      out.view.push_back(static_cast<uint32_t>(s));
    }
  }
  if (loaded == 0) throw IoError(dir, "none of its " + std::to_string(map.size()) + " scan files could be read");
  return out;
}

namespace {

/// '.' and '..' resolved on the text alone; throws when '..' climbs above the root.
std::string normalizeLexically(const std::string& path, const std::string& original) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find('/', start), path.size());
    const std::string part = path.substr(start, end - start);
    if (part == "..") {
      if (parts.empty()) throw ConfigError("output_path '" + original + "' climbs above the root directory");
      parts.pop_back();
    } else if (!part.empty() && part != ".") {
      parts.push_back(part);
    }
    start = end + 1;
  }
  std::string out;
  for (const std::string& p : parts) out += "/" + p;
  return out.empty() ? "/" : out;
}

std::string realDirectory(const std::string& dir, const std::string& what) {
  char buf[PATH_MAX];
  if (!::realpath(dir.c_str(), buf)) throw ConfigError(what + " '" + dir + "' does not exist");
  struct stat st;
  if (::stat(buf, &st) != 0 || !S_ISDIR(st.st_mode)) throw ConfigError(what + " '" + dir + "' is not a directory");
  return buf;
}

}  // namespace

std::string resolveOutputPath(const std::string& path, const std::string& allowed_dir) {
  if (path.empty()) throw ConfigError("output_path is empty");
  if (allowed_dir.empty())
    throw ConfigError("output_path '" + path +
                      "' refused: no output directory is allowed (set parameter 'output_dir')");
  const std::string ext = fileExtension(path);
  if (ext != "stl" && ext != "ply") throw ConfigError("output_path '" + path + "' must end in .stl or .ply");
  const std::string allowed = realDirectory(allowed_dir, "the output directory");
  const std::string full = normalizeLexically(path[0] == '/' ? path : allowed + "/" + path, path);
  const size_t slash = full.rfind('/');
  const std::string name = full.substr(slash + 1);
  const std::string parent = realDirectory(slash == 0 ? "/" : full.substr(0, slash), "the directory of output_path");
  const std::string resolved = (parent == "/" ? "" : parent) + "/" + name;
  if (resolved.compare(0, allowed.size() + 1, allowed + "/") != 0)
    throw ConfigError("output_path '" + path + "' (" + resolved + ") lies outside the output directory " + allowed);
  struct stat st;
  if (::stat(resolved.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw ConfigError("output_path '" + path + "' is a directory");
  return resolved;
}

std::string pointsProblem(const ScanPoints& points, double max_abs_m) {
  if (points.size() == 0) return "there are no finite points to mesh";
  for (size_t i = 0; i < points.size(); ++i)
    if (!points.points[i].allFinite() || points.points[i].cwiseAbs().maxCoeff() > max_abs_m) {
      std::ostringstream out;
      out << "point " << i << " (" << points.points[i].x() << ", " << points.points[i].y() << ", "
          << points.points[i].z() << ") lies beyond " << max_abs_m << " m of the origin (absurd coordinates)";
      return out.str();
    }
  return "";
}

ScanPoints fromCloud(const PointCloud& cloud, const Eigen::Vector3f& viewpoint) {
  ScanPoints out;
  const bool normals = cloud.hasNormals();
  if (!normals) out.origins.push_back(viewpoint);
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points[i].allFinite()) continue;
    out.points.push_back(cloud.points[i]);
    if (normals)
      out.normals.push_back(cloud.normals[i]);
    else
      out.view.push_back(0);
  }
  return out;
}

ScanPoints voxelDownsample(const ScanPoints& in, double voxel_m) {
  if (!(voxel_m > 0.0) || in.points.empty()) return in;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& p : in.points) lo = lo.cwiseMin(p.cast<double>());
  std::vector<std::pair<uint64_t, uint32_t>> keys(in.points.size());
  for (size_t i = 0; i < in.points.size(); ++i) {
    const Eigen::Vector3d c = ((in.points[i].cast<double>() - lo) / voxel_m).array().floor();
    if ((c.array() >= double(1 << 21)).any())
      throw ConfigError("voxel_m = " + std::to_string(voxel_m) + " m is too small for the extent of the points");
    // Morton order: the output (and so normals and Ball Pivoting) reads nearby points from nearby memory.
    keys[i] = {mortonCode(static_cast<uint64_t>(c[0]), static_cast<uint64_t>(c[1]), static_cast<uint64_t>(c[2])),
               static_cast<uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end());
  ScanPoints out;
  out.origins = in.origins;
  const bool normals = !in.normals.empty();
  for (size_t s = 0; s < keys.size();) {
    size_t e = s;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Vector3d nsum = Eigen::Vector3d::Zero();
    while (e < keys.size() && keys[e].first == keys[s].first) {
      sum += in.points[keys[e].second].cast<double>();
      if (normals && in.normals[keys[e].second].allFinite()) nsum += in.normals[keys[e].second].cast<double>();
      ++e;
    }
    out.points.push_back((sum / double(e - s)).cast<float>());
    if (normals) {
      const double len = nsum.norm();
      out.normals.push_back(len > 1e-9 ? Eigen::Vector3f((nsum / len).cast<float>())
                                       : Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
    }
    if (!in.view.empty()) out.view.push_back(in.view[keys[s].second]);
    s = e;
  }
  return out;
}

double meanSpacing(const std::vector<Eigen::Vector3f>& points, size_t max_samples) {
  if (points.size() < 2) return 0.0;
  const std::vector<Eigen::Vector3d> p = toDouble(points);
  Eigen::Vector3d lo = p[0], hi = p[0];
  for (const auto& q : p) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double extent = std::max((hi - lo).maxCoeff(), 1e-9);
  // Points on surfaces: spacing ~ extent / sqrt(n); start a little below that.
  const double guess = extent / std::sqrt(double(p.size()));
  SpatialGrid grid(p, guess);
  const size_t step = std::max<size_t>(1, p.size() / std::max<size_t>(1, max_samples));
  double sum = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < p.size(); i += step) {
    double best = std::numeric_limits<double>::infinity();
    for (double r = 0.25 * guess; r < 4.0 * extent; r *= 2.0) {
      grid.forEachWithin(p[i], r, [&](uint32_t j) {
        // Exact duplicates (real scans repeat points) say nothing about the spacing of the surface.
        const double d2 = (p[j] - p[i]).squaredNorm();
        if (j != i && d2 > 0.0) best = std::min(best, d2);
      });
      if (std::isfinite(best)) break;
    }
    if (!std::isfinite(best)) continue;
    sum += std::sqrt(best);
    ++count;
  }
  return count ? sum / count : 0.0;
}

std::vector<double> automaticRadii(double spacing_m) {
  if (!(spacing_m > 0.0))
    throw ConfigError("cannot choose radii: the mean point spacing is " + std::to_string(spacing_m));
  // A ball touching three neighbours needs at least about their spacing; the larger radii close
  // gaps where the sampling is sparser (thesis 7.4 uses three radii). Larger steps (x2, x4) cost
  // much more on dense noisy maps (the work per pivot grows with r^2) and gave fewer triangles on
  // the 21-scan simulated room.
  return {1.25 * spacing_m, 2.0 * spacing_m, 3.0 * spacing_m};
}

size_t estimateNormals(ScanPoints& pts, double radius_m, int min_neighbors, bool project) {
  requirePositive("normal_radius_m", radius_m, "m");
  if (pts.view.size() != pts.points.size() || pts.origins.empty())
    throw std::invalid_argument("estimateNormals: every point needs a view (scanner position)");
  const std::vector<Eigen::Vector3d> p = toDouble(pts.points);
  SpatialGrid grid(p, radius_m);
  pts.normals.assign(p.size(), Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  size_t usable = 0;
  std::vector<Eigen::Vector3f> projected = pts.points;
  const long n_points = static_cast<long>(p.size());
#pragma omp parallel reduction(+ : usable)
  {
#pragma omp for schedule(dynamic, 4096)
    for (long i = 0; i < n_points; ++i) {
      // One pass over the neighbours: sums of the offsets from p[i] and of their outer products
      // (offsets of a few cm: no cancellation worth mentioning in double).
      const Eigen::Vector3d pi = p[i];
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double sxx = 0, sxy = 0, sxz = 0, syy = 0, syz = 0, szz = 0;
      int count = 0;
      grid.forEachPointWithin(pi, radius_m, [&](uint32_t, const Eigen::Vector3d& q) {
        const Eigen::Vector3d d = q - pi;
        sum += d;
        sxx += d.x() * d.x();
        sxy += d.x() * d.y();
        sxz += d.x() * d.z();
        syy += d.y() * d.y();
        syz += d.y() * d.z();
        szz += d.z() * d.z();
        ++count;
      });
      if (count < min_neighbors) continue;
      const Eigen::Vector3d mean_d = sum / double(count);
      Eigen::Matrix3d cov;
      cov << sxx, sxy, sxz, sxy, syy, syz, sxz, syz, szz;
      cov -= double(count) * mean_d * mean_d.transpose();
      // Closed-form 3x3 eigen decomposition (several times faster than the iterative solver).
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(cov);
      const Eigen::Vector3d ev = es.eigenvalues();  // increasing
      if (!(ev[1] > 1e-3 * ev[2])) continue;        // a line (e.g. one scan row): no plane to take
      Eigen::Vector3d n = es.eigenvectors().col(0);
      const Eigen::Vector3d to_scanner = pts.origins[pts.view[i]].cast<double>() - pi;
      const double c = n.dot(to_scanner) / std::max(to_scanner.norm(), 1e-12);
      if (std::abs(c) < 0.02) continue;  // seen edge-on: the side is unknown
      if (c < 0) n = -n;
      pts.normals[i] = n.cast<float>();
      if (project) projected[i] = (pi - n * n.dot(-mean_d)).cast<float>();
      ++usable;
    }
  }
  if (project) pts.points.swap(projected);
  return usable;
}

void MesherConfig::validate() const {
  requireInRange("voxel_m", voxel_m, 0.0, 10.0, "m");
  requireNonNegative("normal_radius_m", normal_radius_m, "m");
  requireInRange("normal_min_neighbors", normal_min_neighbors, 3, 1000);
  if (radii_m.size() > 32)
    throw ConfigError("radii_m has " + std::to_string(radii_m.size()) + " radii, at most 32 are allowed");
  double prev = 0.0;
  for (size_t k = 0; k < radii_m.size(); ++k) {
    requirePositive("radii_m[" + std::to_string(k) + "]", radii_m[k], "m");
    requireInRange("radii_m[" + std::to_string(k) + "]", radii_m[k], 0.0, 10.0, "m");
    if (radii_m[k] <= prev)
      throw ConfigError("radii_m must increase: radii_m[" + std::to_string(k) + "] = " + std::to_string(radii_m[k]) +
                        " m after " + std::to_string(prev) + " m");
    prev = radii_m[k];
  }
}

MesherResult buildMesh(const ScanPoints& input, const MesherConfig& config) {
  config.validate();
  const auto t0 = std::chrono::steady_clock::now();
  MesherResult res;
  res.input_points = input.size();
  ScanPoints pts = voxelDownsample(input, config.voxel_m);
  res.spacing_m = meanSpacing(pts.points);
  if (pts.normals.empty()) {
    if (pts.size() < 3) throw std::runtime_error("nothing to mesh: " + std::to_string(pts.size()) + " points");
    const double radius = config.normal_radius_m > 0 ? config.normal_radius_m : 3.0 * res.spacing_m;
    estimateNormals(pts, radius, config.normal_min_neighbors, config.smooth);
  }
  res.radii_m = config.radii_m.empty() ? automaticRadii(res.spacing_m) : config.radii_m;
  const auto t1 = std::chrono::steady_clock::now();
  res.prepare_seconds = elapsed(t0);
  BallPivoting bpa(pts.points, pts.normals);
  res.points = bpa.stats().points;
  if (res.points < 3)
    throw std::runtime_error("nothing to mesh: " + std::to_string(res.points) + " of " + std::to_string(input.size()) +
                             " points have a usable normal");
  bpa.run(res.radii_m);  // large maps: slabs on OpenMP threads, seams stitched
  res.mesh = bpa.mesh();
  res.stats = bpa.stats();
  res.bpa_seconds = elapsed(t1);
  res.seconds = elapsed(t0);
  res.topology = analyzeTopology(res.mesh);
  return res;
}

std::vector<double> parseRadii(const std::string& text) {
  std::vector<double> radii;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size()) throw ConfigError("radii: '" + item + "' in '" + text + "' is not a number");
    radii.push_back(v);
  }
  if (radii.empty()) throw ConfigError("radii: empty list '" + text + "'");
  MesherConfig c;
  c.radii_m = radii;
  c.validate();
  return radii;
}

}  // namespace mesher
}  // namespace scanstop
