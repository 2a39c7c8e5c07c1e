// floor_coverage: ground-truth coverage of a simulated run's map, without ROS.
//   floor_coverage WORLD.stl MAP_DIR --start x,y,yaw [--radius R] [--tolerance T] [--config FILE] [--skip-bad]
// Prints one JSON object: the true reachable floor of the world (robot disc of radius R swept from
// the start), how much of it the explorer's floor map (built from MAP_DIR like explorer_node does;
// the map frame is the start pose, as in sim_node) marks floor, and the share. Exit status: 0 ok,
// 2 bad arguments or unreadable input.
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/options.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_eval/ground_truth.h"
#include "scanstop_explorer/parameters.h"

namespace {
constexpr const char* kUsage =
    "usage: floor_coverage WORLD.stl MAP_DIR --start x,y,yaw [--radius R] [--tolerance T] [--config FILE] "
    "[--skip-bad]\n"
    "  WORLD.stl  the simulated world (sim_node's ~world)\n"
    "  MAP_DIR    map directory written by icp_slam_node (poses.csv + scans/)\n"
    "  --start    the robot's start pose in the world [m, m, rad] (= the map frame), |x|, |y| <= 10000\n"
    "  --radius   robot radius for the reachable floor [m], [0.001, 5] (default 0.3, explorer.yaml's robot_radius_m)\n"
    "  --tolerance  map floor this close to a reachable cell observes it [m], [0, 1] (default 0.1: SLAM drift)\n"
    "  --config     explorer parameter file for the floor map (e.g. config/explorer.yaml, as a mission's\n"
    "               explorer_node); default: the explorer's built-in defaults\n"
    "  --skip-bad   use the good scans of a map with bad lines or scan files (each named on stderr);\n"
    "               default: refuse such a map, naming the first problem (exit 2)\n";
}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string world_path, map_path;
  std::optional<Pose2D> start;
  double radius = 0.3, tolerance = 0.1;
  bool skip_bad = false;
  std::string config_file;
  Options opts("floor_coverage", kUsage);
  opts.positional("WORLD.stl", world_path)
      .positional("MAP_DIR", map_path)
      .custom("--start",
              [&](const std::string& v) {
                const std::vector<double> p = parseRealListArg("--start", v, 3, -10000.0, 10000.0, "x,y,yaw");
                start = Pose2D(p[0], p[1], p[2]);
              })
      .real("--radius", radius, 1e-3, 5.0)
      .real("--tolerance", tolerance, 0.0, 1.0)
      .text("--config", config_file)
      .flag("--skip-bad", skip_bad);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  if (!start) {
    std::cerr << "floor_coverage: --start is required\n" << kUsage;
    return kExitUsage;
  }
  try {
    explorer::ExplorerConfig config;
    if (!config_file.empty()) explorer::readParameterFile(config_file, config);
    const TriangleMesh world = readStl(world_path);
    const MapDirectory dir = openMapForTool(
        map_path, skip_bad, [](const std::string& w) { std::cerr << "floor_coverage: warning: " << w << "\n"; });
    std::vector<std::string> problems;
    const eval::GroundTruthCoverage c =
        eval::groundTruthCoverageOfMap(world, *start, dir, radius, tolerance, &problems, config);
    for (size_t k = dir.problems().size(); k < problems.size(); ++k) {
      if (!skip_bad) throw IoError(dir.dir(), problems[k] + " (--skip-bad uses the other scans)");
      std::cerr << "floor_coverage: warning: skipped: " << problems[k] << "\n";
    }
    std::printf("{\"reachable_m2\": %.2f, \"observed_m2\": %.2f, \"coverage\": %.4f, \"scans\": %zu}\n", c.reachable_m2,
                c.observed_m2, c.coverage, c.scans);
  } catch (const std::exception& e) {
    std::cerr << "floor_coverage: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
