// plan_step: one exploration planning step on a saved map directory, without ROS.
//   plan_step MAP_DIR OUT_DIR [--pose x,y,yaw] [--json] [--scale N] [--config FILE] [--skip-bad]
// Writes OUT_DIR/{floor,distance,cost,knowledge,evaluation}.png, path.csv and plan.json; --json
// also prints the plan as one JSON object on stdout. Exit status: 0 planned (or complete),
// 1 planning failed, 2 bad arguments or unreadable input.
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/options.h"
#include "scanstop_explorer/explorer.h"
#include "scanstop_explorer/parameters.h"
#include "scanstop_explorer/render.h"

namespace {
constexpr const char* kUsage =
    "usage: plan_step MAP_DIR OUT_DIR [--pose x,y,yaw] [--json] [--scale N] [--config FILE] [--skip-bad]\n"
    "  MAP_DIR  map directory written by icp_slam_node (poses.csv + scans/)\n"
    "  OUT_DIR  where the images, path.csv and plan.json go (created if missing)\n"
    "  --pose   robot pose in the map frame [m, m, rad], |x|, |y| <= 10000; default: the pose of the last scan\n"
    "  --json   print the plan (path, target, score, complete, coverage) as one JSON object\n"
    "  --scale  image pixels per grid cell, 1-16 (default 2)\n"
    "  --config  explorer parameter file (e.g. config/explorer.yaml: the mission's explorer_node);\n"
    "            default: the explorer's built-in defaults (the thesis' values)\n"
    "  --skip-bad  plan on the good scans of a map with bad lines or scan files (each named on stderr);\n"
    "              default: refuse such a map, naming the first problem (exit 2)\n";

bool isDirectory(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}
}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string map_dir, out_dir;
  std::optional<Pose2D> pose_arg;
  bool json = false, skip_bad = false;
  int scale = 2;
  std::string config_file;
  Options opts("plan_step", kUsage);
  opts.positional("MAP_DIR", map_dir)
      .positional("OUT_DIR", out_dir)
      .custom("--pose",
              [&](const std::string& v) {
                const std::vector<double> p = parseRealListArg("--pose", v, 3, -10000.0, 10000.0, "x,y,yaw");
                pose_arg = Pose2D(p[0], p[1], p[2]);
              })
      .flag("--json", json)
      .integer("--scale", scale, 1, 16)
      .text("--config", config_file)
      .flag("--skip-bad", skip_bad);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  try {
    explorer::ExplorerConfig config;
    if (!config_file.empty()) explorer::readParameterFile(config_file, config);
    const MapDirectory dir = openMapForTool(
        map_dir, skip_bad, [](const std::string& w) { std::cerr << "plan_step: warning: " << w << "\n"; });
    explorer::Explorer ex(config);
    std::vector<std::string> problems;
    ex.loadMapDirectory(dir, &problems);
    // A scan that passed the header check but did not load: refused like any other bad scan.
    for (size_t k = dir.problems().size(); k < problems.size(); ++k) {
      if (!skip_bad) throw IoError(dir.dir(), problems[k] + " (--skip-bad plans without it)");
      std::cerr << "plan_step: warning: skipped: " << problems[k] << "\n";
    }
    const Pose2D pose = pose_arg ? *pose_arg : dir.scans().back().map_pose;
    const explorer::PlanResult r = ex.plan(pose);
    if (!isDirectory(out_dir) && ::mkdir(out_dir.c_str(), 0755) != 0)
      throw IoError(out_dir, std::string("cannot create directory: ") + std::strerror(errno));
    explorer::writePlanImages(r, out_dir, "", scale);
    writeFileAtomic(out_dir + "/path.csv", explorer::pathToCsv(r));
    const std::string j = explorer::planToJson(r);
    writeFileAtomic(out_dir + "/plan.json", j + "\n");
    if (json)
      std::cout << j << std::endl;
    else
      std::cerr << (r.success ? "" : "planning failed: ") << r.message
                << (r.complete ? " (" + r.complete_reason + ")" : "") << "\n";
    return r.success ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "plan_step: " << e.what() << "\n";
    return 2;
  }
}
