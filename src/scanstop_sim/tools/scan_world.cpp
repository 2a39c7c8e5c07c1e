// scan_world WORLD OUT.pcd --pose x,y,yaw [--planes N] [--profile perfect|thesis] [--seed S] [--mixed-pixels]
// Takes one full 3D scan in an STL world without ROS and writes it as an organized PCD in the robot
// frame (base_link; x y z range, NaN for invalid readings).
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/options.h"
#include "scanstop_sim/simulator.h"

namespace {

constexpr const char* kUsage =
    "usage: scan_world WORLD.stl OUT.pcd --pose x,y,yaw [--planes 50|100|200|400] [--profile perfect|thesis] [--seed "
    "S]\n"
    "                  [--mixed-pixels]\n"
    "  --pose          robot pose in the world [m, m, rad], |x|, |y| <= 10000 (required)\n"
    "  --seed          0-9223372036854775807 (default 1)\n"
    "  --mixed-pixels  mixed pixels at depth steps (sim_node's scanner/mixed_pixels; default off)\n"
    "  The world's materials are read from WORLD.materials.yaml next to it when that exists.\n"
    "exit status: 0 written, 2 bad arguments, 1 unreadable world or unwritable output\n";

}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string world_path, out_path, profile = "perfect", planes_text = "400";
  std::optional<Pose2D> pose;
  long seed = 1;
  bool mixed_pixels = false;
  Options opts("scan_world", kUsage);
  opts.positional("WORLD.stl", world_path)
      .positional("OUT.pcd", out_path)
      .custom("--pose",
              [&](const std::string& v) {
                const std::vector<double> p = parseRealListArg("--pose", v, 3, -1e4, 1e4, "x,y,yaw");
                pose = Pose2D(p[0], p[1], p[2]);
              })
      .choice("--planes", planes_text, {"50", "100", "200", "400"})
      .choice("--profile", profile, {"perfect", "thesis"})
      .integer("--seed", seed, 0L, std::numeric_limits<long>::max())
      .flag("--mixed-pixels", mixed_pixels);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  if (!pose) {
    std::cerr << "scan_world: --pose is required\n" << kUsage;
    return kExitUsage;
  }
  const int planes = std::stoi(planes_text);
  try {
    const std::string out_problem = outputFileProblem(out_path);  // before the scan, not after it
    if (!out_problem.empty()) throw IoError(out_path, "cannot write: " + out_problem);
    scanstop::sim::keepLargeBuffersMapped();
    scanstop::sim::SimConfig config;
    config.errors = scanstop::sim::makeProfile(profile);
    config.seed = static_cast<uint64_t>(seed);
    config.scanner.mixed_pixels = mixed_pixels;
    scanstop::sim::Simulator sim(scanstop::sim::World::load(world_path), config, *pose);
    const scanstop::sim::ScanOutput scan = sim.scan(planes);
    scanstop::writeCloud(out_path, scan.cloud);
    std::cout << out_path << ": " << scan.cloud.height << " planes x " << scan.cloud.width << " beams, "
              << scan.valid_points << " valid points, " << scan.planes_dropped << " planes dropped, "
              << scan.outliers_removed << " outliers removed";
    if (mixed_pixels) std::cout << ", " << scan.mixed_pixels << " mixed pixels";
    std::cout << "\n";
  } catch (const std::exception& e) {
    std::cerr << "scan_world: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
