// plan_step: one exploration planning step on a saved map directory, without ROS.
//   plan_step MAP_DIR OUT_DIR [--pose x,y,yaw] [--json] [--scale N]
// Writes OUT_DIR/{floor,distance,cost,knowledge,evaluation}.png, path.csv and plan.json; --json
// also prints the plan as one JSON object on stdout. Exit status: 0 planned (or complete),
// 1 planning failed, 2 bad arguments or unreadable input.
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_explorer/explorer.h"
#include "scanstop_explorer/render.h"

namespace {
constexpr const char* kUsage =
    "usage: plan_step MAP_DIR OUT_DIR [--pose x,y,yaw] [--json] [--scale N]\n"
    "  MAP_DIR  map directory written by icp_slam_node (poses.csv + scans/)\n"
    "  OUT_DIR  where the images, path.csv and plan.json go (created if missing)\n"
    "  --pose   robot pose in the map frame [m, m, rad]; default: the pose of the last scan\n"
    "  --json   print the plan (path, target, score, complete, coverage) as one JSON object\n"
    "  --scale  image pixels per grid cell (default 2)\n";

bool isDirectory(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}
}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string map_dir, out_dir, pose_text;
  bool json = false;
  int scale = 2;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--json") json = true;
    else if (a == "--pose" && i + 1 < argc) pose_text = argv[++i];
    else if (a == "--scale" && i + 1 < argc) scale = std::atoi(argv[++i]);
    else if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    } else if (!a.empty() && a[0] != '-' && map_dir.empty()) map_dir = a;
    else if (!a.empty() && a[0] != '-' && out_dir.empty()) out_dir = a;
    else {
      std::cerr << "plan_step: unexpected argument '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (map_dir.empty() || out_dir.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  if (scale < 1 || scale > 16) {
    std::cerr << "plan_step: --scale must be in [1, 16]\n";
    return 2;
  }
  try {
    if (!isDirectory(map_dir)) throw IoError(map_dir, "no such map directory");
    const MapDirectory dir(map_dir);
    if (dir.size() == 0) throw IoError(dir.posesPath(), "the map directory holds no scans");
    explorer::Explorer ex;
    ex.loadMapDirectory(dir);
    const Pose2D pose = pose_text.empty() ? dir.scans().back().map_pose : parsePose2D(pose_text);
    const explorer::PlanResult r = ex.plan(pose);
    if (!isDirectory(out_dir) && ::mkdir(out_dir.c_str(), 0755) != 0)
      throw IoError(out_dir, std::string("cannot create directory: ") + std::strerror(errno));
    explorer::writePlanImages(r, out_dir, "", scale);
    writeFileAtomic(out_dir + "/path.csv", explorer::pathToCsv(r));
    const std::string j = explorer::planToJson(r);
    writeFileAtomic(out_dir + "/plan.json", j + "\n");
    if (json) std::cout << j << std::endl;
    else std::cerr << (r.success ? "" : "planning failed: ") << r.message
                   << (r.complete ? " (" + r.complete_reason + ")" : "") << "\n";
    return r.success ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "plan_step: " << e.what() << "\n";
    return 2;
  }
}
