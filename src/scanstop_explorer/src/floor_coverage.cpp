// floor_coverage: ground-truth coverage of a simulated run's map, without ROS.
//   floor_coverage WORLD.stl MAP_DIR --start x,y,yaw [--radius R] [--tolerance T]
// Prints one JSON object: the true reachable floor of the world (robot disc of radius R swept from
// the start), how much of it the explorer's floor map (built from MAP_DIR like explorer_node does;
// the map frame is the start pose, as in sim_node) marks floor, and the share. Exit status: 0 ok,
// 2 bad arguments or unreadable input.
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "scanstop_common/map_dir.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_explorer/ground_truth.h"

namespace {
constexpr const char* kUsage =
    "usage: floor_coverage WORLD.stl MAP_DIR --start x,y,yaw [--radius R] [--tolerance T]\n"
    "  WORLD.stl  the simulated world (sim_node's ~world)\n"
    "  MAP_DIR    map directory written by icp_slam_node (poses.csv + scans/)\n"
    "  --start    the robot's start pose in the world [m, m, rad] (= the map frame)\n"
    "  --radius   robot radius for the reachable floor [m] (default 0.3, explorer.yaml's robot_radius_m)\n"
    "  --tolerance  map floor this close to a reachable cell observes it [m] (default 0.1: SLAM drift)\n";
}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::vector<std::string> pos;
  std::string start_text;
  double radius = 0.3, tolerance = 0.1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--start" && i + 1 < argc) start_text = argv[++i];
    else if (a == "--radius" && i + 1 < argc) radius = std::atof(argv[++i]);
    else if (a == "--tolerance" && i + 1 < argc) tolerance = std::atof(argv[++i]);
    else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      std::cerr << "floor_coverage: unknown option '" << a << "'\n" << kUsage;
      return 2;
    } else {
      pos.push_back(a);
    }
  }
  if (pos.size() != 2 || start_text.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  if (!(radius > 0.0 && radius <= 5.0) || !(tolerance >= 0.0 && tolerance <= 1.0)) {
    std::cerr << "floor_coverage: --radius must be in (0, 5] m and --tolerance in [0, 1] m\n";
    return 2;
  }
  try {
    const Pose2D start = parsePose2D(start_text);
    const TriangleMesh world = readStl(pos[0]);
    struct stat st;
    if (::stat(pos[1].c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
      throw std::invalid_argument("map directory " + pos[1] + " does not exist");
    const MapDirectory dir(pos[1]);
    std::vector<std::string> problems;
    const explorer::GroundTruthCoverage c = explorer::groundTruthCoverageOfMap(world, start, dir, radius, tolerance, &problems);
    for (const std::string& p : problems) std::cerr << "floor_coverage: " << p << "\n";
    std::printf("{\"reachable_m2\": %.2f, \"observed_m2\": %.2f, \"coverage\": %.4f, \"scans\": %zu}\n", c.reachable_m2,
                c.observed_m2, c.coverage, c.scans);
  } catch (const std::exception& e) {
    std::cerr << "floor_coverage: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
