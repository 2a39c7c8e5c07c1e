// make_worlds OUT_DIR [--furnished SEED ...]: writes the project's simulated worlds (binary STL)
// into OUT_DIR and prints each world's size, triangle count and documented start pose. The worlds in
// worlds/ are this tool's output: `rosrun scanstop_sim make_worlds worlds` regenerates them byte for
// byte. With --furnished it writes only the furnished flats of the given seeds (furnished_<SEED>.stl;
// the committed ones are seeds 1-3), so that a benchmark can run many layouts.
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/options.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_sim/world_builder.h"

namespace {
constexpr const char* kUsage =
    "usage: make_worlds OUT_DIR [--furnished SEED ...]\n"
    "  writes the project's worlds (or only furnished_<SEED>.stl for each SEED, 0-999999999) into OUT_DIR\n"
    "  (OUT_DIR must exist)\n";
}  // namespace

int main(int argc, char** argv) {
  std::string out_dir;
  std::vector<std::string> seed_texts;
  bool furnished = false;
  scanstop::Options opts("make_worlds", kUsage);
  opts.positional("OUT_DIR", out_dir).flag("--furnished", furnished).rest("SEED", seed_texts);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  std::vector<unsigned> seeds;
  try {
    if (!seed_texts.empty() && !furnished)
      throw scanstop::ConfigError("unexpected argument " + seed_texts.front() + " (seeds follow --furnished)");
    for (const std::string& a : seed_texts)
      seeds.push_back(static_cast<unsigned>(scanstop::parseIntegerArg("--furnished seed", a, 0, 999999999)));
    if (furnished && seeds.empty()) throw scanstop::ConfigError("--furnished needs at least one seed");
  } catch (const scanstop::ConfigError& e) {
    std::cerr << "make_worlds: " << e.what() << "\n" << kUsage;
    return scanstop::kExitUsage;
  }
  try {
    std::vector<scanstop::sim::WorldSpec> worlds;
    if (furnished)
      for (const unsigned s : seeds) worlds.push_back(scanstop::sim::furnishedWorld(s));
    else
      worlds = scanstop::sim::buildWorlds();
    for (const auto& w : worlds) {
      const std::string path = out_dir + "/" + w.name + ".stl";
      scanstop::writeStlBinary(path, w.mesh);
      if (!w.materials_yaml.empty())
        scanstop::writeFileAtomic(out_dir + "/" + w.name + ".materials.yaml", w.materials_yaml);
      std::printf("%-12s %5.1f x %4.1f m  %6zu triangles  start (%.2f, %.2f, %.2f rad)  %s\n", w.name.c_str(),
                  w.size_m.x(), w.size_m.y(), w.mesh.faces.size(), w.start.x, w.start.y, w.start.yaw, path.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "make_worlds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
