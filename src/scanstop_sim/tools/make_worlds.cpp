// make_worlds OUT_DIR: writes the project's simulated worlds (binary STL) into OUT_DIR and prints
// each world's size, triangle count and documented start pose. The worlds in worlds/ are this
// tool's output: `rosrun scanstop_sim make_worlds worlds` regenerates them byte for byte.
#include <cstdio>
#include <iostream>

#include "scanstop_common/error.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_sim/world_builder.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_worlds OUT_DIR\n";
    return 2;
  }
  try {
    for (const auto& w : scanstop::sim::buildWorlds()) {
      const std::string path = std::string(argv[1]) + "/" + w.name + ".stl";
      scanstop::writeStlBinary(path, w.mesh);
      std::printf("%-12s %5.1f x %4.1f m  %5zu triangles  start (%.2f, %.2f, %.2f rad)  %s\n", w.name.c_str(),
                  w.size_m.x(), w.size_m.y(), w.mesh.faces.size(), w.start.x, w.start.y, w.start.yaw, path.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "make_worlds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
