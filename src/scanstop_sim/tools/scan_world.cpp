// scan_world WORLD OUT.pcd --pose x,y,yaw [--planes N] [--profile perfect|thesis] [--seed S]
// Takes one full 3D scan in an STL world without ROS and writes it as an organized PCD in the robot
// frame (base_link; x y z range, NaN for invalid readings).
#include <cstdlib>
#include <iostream>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_sim/simulator.h"

namespace {

int usage(const std::string& why) {
  std::cerr << "scan_world: " << why << "\n"
            << "usage: scan_world WORLD.stl OUT.pcd --pose x,y,yaw [--planes 50|100|200|400] "
               "[--profile perfect|thesis] [--seed S]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage("need a world and an output file");
  const std::string world_path = argv[1], out_path = argv[2];
  std::string pose_text, profile = "perfect";
  int planes = 400;
  long seed = 1;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return usage("missing value after " + arg);
    const std::string value = argv[++i];
    if (arg == "--pose") pose_text = value;
    else if (arg == "--planes") planes = std::atoi(value.c_str());
    else if (arg == "--profile") profile = value;
    else if (arg == "--seed") seed = std::atol(value.c_str());
    else return usage("unknown option " + arg);
  }
  if (pose_text.empty()) return usage("--pose is required");
  if (planes != 50 && planes != 100 && planes != 200 && planes != 400) return usage("--planes must be 50, 100, 200 or 400");
  try {
    scanstop::sim::keepLargeBuffersMapped();
    scanstop::sim::SimConfig config;
    config.errors = scanstop::sim::makeProfile(profile);
    config.seed = static_cast<uint64_t>(seed);
    scanstop::sim::Simulator sim(scanstop::sim::World::load(world_path), config, scanstop::parsePose2D(pose_text));
    const scanstop::sim::ScanOutput scan = sim.scan(planes);
    scanstop::writeCloud(out_path, scan.cloud);
    std::cout << out_path << ": " << scan.cloud.height << " planes x " << scan.cloud.width << " beams, "
              << scan.valid_points << " valid points, " << scan.planes_dropped << " planes dropped, "
              << scan.outliers_removed << " outliers removed\n";
  } catch (const std::exception& e) {
    std::cerr << "scan_world: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
