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
#include "scanstop_common/stl_io.h"
#include "scanstop_sim/world_builder.h"

namespace {
int usage() {
  std::cerr << "usage: make_worlds OUT_DIR [--furnished SEED ...]\n"
               "  writes the project's worlds (or only furnished_<SEED>.stl for each SEED, 0-999999999) into OUT_DIR\n";
  return 2;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") return usage();
  std::vector<unsigned> seeds;
  bool furnished = false;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--furnished") {
      furnished = true;
      continue;
    }
    if (!furnished || a.empty() || a.size() > 9 || a.find_first_not_of("0123456789") != std::string::npos) {
      std::cerr << "make_worlds: '" << a << "' is not a seed (a whole number 0-999999999 after --furnished)\n";
      return usage();
    }
    seeds.push_back(static_cast<unsigned>(std::stoul(a)));
  }
  if (furnished && seeds.empty()) {
    std::cerr << "make_worlds: --furnished needs at least one seed\n";
    return usage();
  }
  try {
    std::vector<scanstop::sim::WorldSpec> worlds;
    if (furnished)
      for (const unsigned s : seeds) worlds.push_back(scanstop::sim::furnishedWorld(s));
    else
      worlds = scanstop::sim::buildWorlds();
    for (const auto& w : worlds) {
      const std::string path = std::string(argv[1]) + "/" + w.name + ".stl";
      scanstop::writeStlBinary(path, w.mesh);
      std::printf("%-12s %5.1f x %4.1f m  %6zu triangles  start (%.2f, %.2f, %.2f rad)  %s\n", w.name.c_str(),
                  w.size_m.x(), w.size_m.y(), w.mesh.faces.size(), w.start.x, w.start.y, w.start.yaw, path.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "make_worlds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
