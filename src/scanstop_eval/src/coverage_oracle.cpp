#include "scanstop_eval/coverage_oracle.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_eval/ground_truth.h"
#include "scanstop_eval/surface_elements.h"

namespace scanstop {
namespace eval {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The centre cell nearest to (x, y) within the square of half-width half_m about it, if any.
std::optional<Eigen::Vector2d> nearestCentre(const ReachableFloor& floor, double x, double y, double half_m) {
  const explorer::GridGeometry& g = floor.geometry;
  const cv::Point c = g.cellOf(x, y);
  if (g.contains(c) && floor.centres.at<uint8_t>(c)) return Eigen::Vector2d(x, y);
  const int r = static_cast<int>(std::ceil(half_m / g.resolution));
  std::optional<Eigen::Vector2d> best;
  double best_d2 = 0.0;
  for (int row = std::max(0, c.y - r); row <= std::min(g.height - 1, c.y + r); ++row)
    for (int col = std::max(0, c.x - r); col <= std::min(g.width - 1, c.x + r); ++col) {
      if (!floor.centres.at<uint8_t>(row, col)) continue;
      const Eigen::Vector2d p = g.center({col, row});
      const Eigen::Vector2d d = p - Eigen::Vector2d(x, y);
      if (d.cwiseAbs().maxCoeff() >= half_m || (best && d.squaredNorm() >= best_d2)) continue;
      best = p;
      best_d2 = d.squaredNorm();
    }
  return best;
}

/// One candidate per square of a lattice through the start (spacing grid_m) that holds a place for
/// the disc's centre: the lattice point itself, or the centre cell nearest to it in its square (so
/// that a passage whose centres are narrower than the lattice gets candidates too).
std::vector<Eigen::Vector2d> latticeOnCentres(const ReachableFloor& floor, const Pose2D& start, double grid_m) {
  const explorer::GridGeometry& g = floor.geometry;
  const double x0 = g.origin_x, y0 = g.origin_y, x1 = x0 + g.width * g.resolution, y1 = y0 + g.height * g.resolution;
  const long i0 = -static_cast<long>(std::floor((start.x - x0) / grid_m)),
             i1 = static_cast<long>((x1 - start.x) / grid_m);
  const long j0 = -static_cast<long>(std::floor((start.y - y0) / grid_m)),
             j1 = static_cast<long>((y1 - start.y) / grid_m);
  std::vector<Eigen::Vector2d> out;
  for (long j = j0; j <= j1; ++j)
    for (long i = i0; i <= i1; ++i)
      if (const auto p = nearestCentre(floor, start.x + i * grid_m, start.y + j * grid_m, grid_m / 2))
        out.push_back(*p);
  return out;
}

/// The reachable floor cells, numbered, and which of them a point marks as seen. A cell of k x k
/// raster cells of the true reachable floor is a reachable floor cell when one of them is reachable.
class FloorCells {
 public:
  FloorCells(const ReachableFloor& floor, int k) : g_(floor.geometry) {
    g_.resolution *= k;
    g_.width = (g_.width + k - 1) / k;
    g_.height = (g_.height + k - 1) / k;
    id_.assign(static_cast<size_t>(g_.width) * g_.height, -1);
    for (int r = 0; r < floor.reachable.rows; ++r)
      for (int c = 0; c < floor.reachable.cols; ++c) {
        int32_t& id = id_[(r / k) * g_.width + c / k];
        if (floor.reachable.at<uint8_t>(r, c) && id < 0) id = static_cast<int32_t>(count_++);
      }
  }
  size_t size() const { return count_; }

  /// Calls f(id) for every reachable cell within radius_m of (x, y) [m]: its centre when
  /// `to_centre`, else any part of its square.
  template <class F>
  void forEachNear(double x, double y, double radius_m, bool to_centre, F&& f) const {
    const int r = static_cast<int>(std::ceil(radius_m / g_.resolution));
    const cv::Point c = g_.cellOf(x, y);
    const double r2 = radius_m * radius_m, half = to_centre ? 0.0 : g_.resolution / 2;
    for (int row = std::max(0, c.y - r); row <= std::min(g_.height - 1, c.y + r); ++row)
      for (int col = std::max(0, c.x - r); col <= std::min(g_.width - 1, c.x + r); ++col) {
        const int32_t id = id_[row * g_.width + col];
        if (id < 0) continue;
        const Eigen::Vector2d d = ((g_.center({col, row}) - Eigen::Vector2d(x, y)).cwiseAbs().array() - half).max(0.0);
        if (d.squaredNorm() <= r2) f(static_cast<uint32_t>(id));
      }
  }

 private:
  explorer::GridGeometry g_;
  std::vector<int32_t> id_;
  size_t count_ = 0;
};

/// Collects the ids a candidate sees once each (stamp: the candidate's number + 1 per element).
struct SeenSet {
  std::vector<uint32_t> stamp;
  uint32_t current = 0;
  ElementSet ids;
  void start(uint32_t candidate_number) {
    current = candidate_number;
    ids.clear();
  }
  void add(uint32_t id) {
    if (stamp[id] == current) return;
    stamp[id] = current;
    ids.push_back(id);
  }
};

/// The candidate's perfect scan, its points in the world frame.
std::vector<Eigen::Vector3f> scanAt(sim::Simulator& sim, const Pose2D& pose, int planes) {
  sim.reset(pose, -1);
  const sim::ScanOutput scan = sim.scan(planes);
  const Eigen::Isometry3f T_world_base = pose.toIsometry3f();
  std::vector<Eigen::Vector3f> out;
  out.reserve(scan.valid_points);
  for (const Eigen::Vector3f& p : scan.cloud.points)
    if (p.allFinite()) out.push_back(T_world_base * p);
  return out;
}

/// What each scanned candidate saw.
struct Sightings {
  std::vector<Eigen::Vector2d> candidates;  ///< scanned positions
  size_t refused = 0;                       ///< positions the simulator refused
  std::vector<ElementSet> floor, surface;   ///< per scanned candidate
};

/// Scans at every lattice point (heading yaw) and records the floor cells (floor hits within
/// floor_tolerance_m, cells within known_free_m of the pose) and surface elements each scan sees.
Sightings scanCandidates(sim::Simulator& sim, const std::vector<Eigen::Vector2d>& lattice, double yaw,
                         const FloorCells& floor, const SurfaceElements& surface, const OracleConfig& config,
                         const std::function<void(size_t, size_t)>& progress) {
  Sightings out;
  SeenSet seen_floor{std::vector<uint32_t>(floor.size(), 0), 0, {}};
  SeenSet seen_surface{std::vector<uint32_t>(surface.size(), 0), 0, {}};
  const float surface_tol = static_cast<float>(config.surface_tolerance_m);
  for (size_t i = 0; i < lattice.size(); ++i) {
    const Pose2D pose(lattice[i].x(), lattice[i].y(), yaw);
    std::vector<Eigen::Vector3f> points;
    try {
      points = scanAt(sim, pose, config.planes);
    } catch (const std::invalid_argument&) {  // the simulator's exact disc touches an obstacle here
      ++out.refused;
      if (progress) progress(i + 1, lattice.size());
      continue;
    }
    seen_floor.start(static_cast<uint32_t>(out.candidates.size() + 1));
    seen_surface.start(static_cast<uint32_t>(out.candidates.size() + 1));
    floor.forEachNear(pose.x, pose.y, config.known_free_m, true, [&](uint32_t id) { seen_floor.add(id); });
    for (const Eigen::Vector3f& p : points) {
      if (p.z() < config.z_lo_m)
        floor.forEachNear(p.x(), p.y(), config.floor_tolerance_m, false, [&](uint32_t id) { seen_floor.add(id); });
      else
        surface.forEachNear(p, surface_tol, [&](uint32_t id) { seen_surface.add(id); });
    }
    out.candidates.push_back(lattice[i]);
    out.floor.push_back(seen_floor.ids);
    out.surface.push_back(seen_surface.ids);
    if (progress) progress(i + 1, lattice.size());
  }
  return out;
}

size_t unionSize(const std::vector<ElementSet>& sets, size_t universe) {
  std::vector<uint8_t> in(universe, 0);
  for (const ElementSet& s : sets)
    for (const uint32_t id : s) in[id] = 1;
  return static_cast<size_t>(std::count(in.begin(), in.end(), 1));
}

CoverResult coverOf(const std::vector<ElementSet>& sets, size_t universe, size_t total, const OracleConfig& config) {
  CoverResult out;
  out.total = total;
  out.greedy = greedyCover(sets, universe);
  out.targets = scansNeeded(out.greedy, total, config.shares, std::nullopt);
  const bool pairs_may_help = std::any_of(out.targets.begin(), out.targets.end(),
                                          [](const CoverTarget& t) { return t.scans && *t.scans >= 3; });
  if (pairs_may_help && config.max_pair_work > 0) {
    out.best_pair = bestPairCoverage(sets, universe, config.max_pair_work);
    out.targets = scansNeeded(out.greedy, total, config.shares, out.best_pair);
  }
  return out;
}

/// What the oracle scans in: the true reachable floor, its cells, the surface elements and the
/// candidate lattice.
struct Scene {
  Scene(const TriangleMesh& mesh, const Pose2D& start, const OracleConfig& config)
      : truth(reachableFloor(mesh, start, config.robot_radius_m, config.raster_m, config.z_lo_m, config.z_hi_m)),
        floor(truth, config.cellsPerFloorCell()),
        surface(mesh, config.surface_cell_m, config.z_lo_m),
        lattice(latticeOnCentres(truth, start, config.grid_m)) {}
  ReachableFloor truth;
  FloorCells floor;
  SurfaceElements surface;
  std::vector<Eigen::Vector2d> lattice;
};

}  // namespace

void OracleConfig::validate() const {
  requireInRange("grid_m", grid_m, 0.05, 10.0, "m");
  requireInRange("planes", planes, 1, 2000);
  requireInRange("robot_radius_m", robot_radius_m, 1e-3, 5.0, "m");
  requireInRange("raster_m", raster_m, 0.01, 1.0, "m");
  requireInRange("cell_m", cell_m, raster_m, 1.0, "m");
  if (std::abs(cellsPerFloorCell() * raster_m - cell_m) > 1e-6 * cell_m)
    throw ConfigError("cell_m = " + std::to_string(cell_m) +
                      " m is not a whole multiple of raster_m = " + std::to_string(raster_m) + " m");
  requireInRange("floor_tolerance_m", floor_tolerance_m, 0.0, 1.0, "m");
  requireInRange("known_free_m", known_free_m, 0.0, 5.0, "m");
  requireInRange("surface_cell_m", surface_cell_m, 0.01, 1.0, "m");
  requireInRange("surface_tolerance_m", surface_tolerance_m, 0.0, surface_cell_m, "m");
  requireInRange("z_lo_m", z_lo_m, 0.0, 1.0, "m");
  requireInRange("z_hi_m", z_hi_m, z_lo_m + 1e-3, 5.0, "m");
  for (const double s : shares) requireInRange("shares", s, 0.0, 1.0);
  requireNonNegative("max_pair_work", max_pair_work);
}

int OracleConfig::cellsPerFloorCell() const { return std::max(1, static_cast<int>(std::lround(cell_m / raster_m))); }

double CoverResult::shareAfter(size_t k) const {
  if (k == 0 || greedy.covered.empty() || total == 0) return 0.0;
  return static_cast<double>(greedy.covered[std::min(k, greedy.covered.size()) - 1]) / static_cast<double>(total);
}

OracleResult runCoverageOracle(sim::Simulator& sim, const Pose2D& start, const OracleConfig& config,
                               const std::function<void(size_t, size_t)>& progress) {
  config.validate();
  Clock::time_point t0 = Clock::now();
  const Scene scene(sim.world().mesh(), start, config);
  const FloorCells& floor = scene.floor;
  const SurfaceElements& surface = scene.surface;
  OracleResult out;
  out.start = start;
  out.floor_cells = floor.size();
  out.reachable_m2 = scene.truth.reachable_m2;
  out.surface_elements = surface.size();
  out.setup_s = secondsSince(t0);

  t0 = Clock::now();
  Sightings seen = scanCandidates(sim, scene.lattice, start.yaw, floor, surface, config, progress);
  out.candidates = std::move(seen.candidates);
  out.candidates_refused = seen.refused;
  out.scan_s = secondsSince(t0);

  t0 = Clock::now();
  out.floor_seen = unionSize(seen.floor, floor.size());
  out.surface_visible = unionSize(seen.surface, surface.size());
  out.floor = coverOf(seen.floor, floor.size(), floor.size(), config);
  out.surface = coverOf(seen.surface, surface.size(), out.surface_visible, config);
  out.cover_s = secondsSince(t0);
  return out;
}

VisibleSurface visibleSurface(sim::Simulator& sim, const Pose2D& start, const OracleConfig& config,
                              const std::function<void(size_t, size_t)>& progress) {
  config.validate();
  const Clock::time_point t0 = Clock::now();
  Scene scene(sim.world().mesh(), start, config);
  const Sightings seen = scanCandidates(sim, scene.lattice, start.yaw, scene.floor, scene.surface, config, progress);
  VisibleSurface out{std::move(scene.surface), {}, 0, seen.candidates.size(), seen.refused, 0.0};
  out.visible.assign(out.elements.size(), 0);
  for (const ElementSet& s : seen.surface)
    for (const uint32_t id : s) out.visible[id] = 1;
  out.visible_count = static_cast<size_t>(std::count(out.visible.begin(), out.visible.end(), 1));
  out.seconds = secondsSince(t0);
  return out;
}

}  // namespace eval
}  // namespace scanstop
