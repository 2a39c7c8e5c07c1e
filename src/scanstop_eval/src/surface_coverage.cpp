#include "scanstop_eval/surface_coverage.h"

#include <exception>
#include <utility>

#include "scanstop_common/config.h"

namespace scanstop {
namespace eval {

SurfaceCoverage::SurfaceCoverage(const VisibleSurface& visible, double tolerance_m)
    : visible_(visible), tolerance_(static_cast<float>(tolerance_m)), held_(visible.elements.size(), 0) {
  requireInRange("surface tolerance", tolerance_m, 0.0, visible.elements.cell(), "m");
}

void SurfaceCoverage::add(const std::vector<Eigen::Vector3f>& points_world) {
  for (const Eigen::Vector3f& p : points_world) {
    if (!p.allFinite()) continue;
    ++points_;
    visible_.elements.forEachNear(p, tolerance_, [this](uint32_t id) {
      if (held_[id] || !visible_.visible[id]) return;
      held_[id] = 1;
      ++covered_;
    });
  }
}

double SurfaceCoverage::share() const {
  return visible() ? static_cast<double>(covered_) / static_cast<double>(visible()) : 0.0;
}

MapSurfaceCoverage mapSurfaceCoverage(const VisibleSurface& visible, const MapDirectory& map, const Pose2D& world_T_map,
                                      double tolerance_m, std::vector<std::string>* problems) {
  SurfaceCoverage coverage(visible, tolerance_m);
  const Eigen::Isometry3f T = world_T_map.toIsometry3f();
  MapSurfaceCoverage out;
  if (problems)
    for (const MapProblem& p : map.problems()) problems->push_back(p.message());
  std::vector<Eigen::Vector3f> world;
  for (size_t i = 0; i < map.size(); ++i) {
    PointCloud cloud;
    try {
      cloud = map.loadScanInMap(i);
    } catch (const std::exception& e) {
      if (problems) problems->push_back("scan " + std::to_string(map.scans()[i].index) + " skipped: " + e.what());
      continue;
    }
    world.clear();
    world.reserve(cloud.points.size());
    for (const Eigen::Vector3f& p : cloud.points) world.push_back(T * p);
    coverage.add(world);
    ++out.scans;
  }
  out.points = coverage.points();
  out.visible = coverage.visible();
  out.covered = coverage.covered();
  out.share = coverage.share();
  return out;
}

RunSurfaceCoverage surfaceCoverageOfRun(const TriangleMesh& world, const std::string& world_name, const Pose2D& start,
                                        const MapDirectory& map, double robot_radius_m, int planes) {
  sim::SimConfig sim_config;
  sim_config.errors = sim::makeProfile("perfect");
  sim::Simulator sim(sim::World::fromMesh(world, world_name), sim_config, start);
  OracleConfig oracle;
  oracle.planes = planes;
  oracle.robot_radius_m = robot_radius_m;
  VisibleSurface visible = visibleSurface(sim, start, oracle);
  const MapSurfaceCoverage held = mapSurfaceCoverage(visible, map, start, oracle.surface_tolerance_m);
  const size_t candidates = visible.candidates;
  const double seconds = visible.seconds;
  return RunSurfaceCoverage{held, candidates, seconds, std::move(visible)};
}

}  // namespace eval
}  // namespace scanstop
