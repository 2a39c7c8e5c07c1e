// surface_accuracy WORLD.stl INPUT [--start x,y,yaw] [--tolerance M] [--sample M] [--planes N] [--json]
// A map's or a mesh's accuracy against the world it was made in (issue #20 point 4): the distance of
// its points (a mesh: its vertices and area-weighted samples on its faces) to the world's true
// surfaces, and the share of the visible surface (the coverage oracle's) it covers within 3 cm.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/options.h"
#include "scanstop_common/robot_body.h"
#include "scanstop_eval/surface_accuracy.h"
#include "scanstop_explorer/parameters.h"

namespace {

constexpr const char* kUsage =
    "usage: surface_accuracy WORLD.stl INPUT [--start x,y,yaw] [--tolerance M] [--sample M] [--planes N] [--json]\n"
    "                        [--skip-bad]\n"
    "  WORLD.stl      the simulated world (sim_node's ~world)\n"
    "  INPUT          what is measured, in the map frame: a mesh (.ply with faces, .stl), a point cloud (.ply\n"
    "                 without faces, .pcd, .xyz, .txt) or a map directory (every scan at its final map pose)\n"
    "  --start        the simulated start pose in the world = the map frame's pose [m, m, rad], |x|, |y| <= 10000\n"
    "                 (default: the world's documented start pose, as sim_node)\n"
    "  --tolerance    a visible surface element is covered when a point lies this close to it [m], [0, surface\n"
    "                 cell] (default 0.03)\n"
    "  --sample       spacing of a mesh's area-weighted face samples [m], [0.001, 1] (default 0.01)\n"
    "  --planes       planes of the oracle's scans that define the visible surface (default 400)\n"
    "  --surface-cell visible surface element size [m], [0.01, 1] (default 0.05)\n"
    "  --grid         oracle candidate spacing [m], [0.05, 10] (default 0.5)\n"
    "  --no-coverage  distances only: no visible surface (no simulated scans)\n"
    "  --json         one JSON object on stdout instead of the text report\n"
    "  --quiet        no progress on stderr\n"
    "  --skip-bad     measure a map directory without its bad scans or lines (each named in a warning); without\n"
    "                 it a bad one is an error that names it\n"
    "exit status: 0 done, 2 bad arguments, 1 unreadable world or input, or a bad start pose\n";

using scanstop::jsonNumber;
using scanstop::eval::DistanceStats;

std::string statsJson(const DistanceStats& s) {
  std::ostringstream o;
  o << "{\"count\": " << s.count << ", \"median_m\": " << jsonNumber(s.median_m, 6)
    << ", \"mean_m\": " << jsonNumber(s.mean_m, 6) << ", \"rms_m\": " << jsonNumber(s.rms_m, 6)
    << ", \"p95_m\": " << jsonNumber(s.p95_m, 6) << ", \"max_m\": " << jsonNumber(s.max_m, 6) << ", \"within\": {";
  for (size_t k = 0; k < s.within_m.size(); ++k)
    o << (k ? ", " : "") << "\"" << s.within_m[k] << "\": " << jsonNumber(s.share[k], 6);
  o << "}}";
  return o.str();
}

void printStats(const char* what, const DistanceStats& s) {
  std::printf("%-28s n %zu: median %.2f mm, mean %.2f mm, RMS %.2f mm, p95 %.2f mm, max %.1f mm; within", what, s.count,
              1e3 * s.median_m, 1e3 * s.mean_m, 1e3 * s.rms_m, 1e3 * s.p95_m, 1e3 * s.max_m);
  for (size_t k = 0; k < s.within_m.size(); ++k)
    std::printf("%s %g cm %.1f %%", k ? "," : "", 100 * s.within_m[k], 100 * s.share[k]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string world_path, input_path, start_text, planes_text = "400";
  bool json = false, quiet = false, no_coverage = false, skip_bad = false;
  eval::AccuracyConfig config;
  eval::OracleConfig oracle;
  oracle.robot_radius_m = RobotBody().radius_m + explorer::BodyMargins().inflation_margin_m;
  oracle.z_hi_m = RobotBody().height_m + explorer::BodyMargins().obstacle_height_margin_m;
  Options opts("surface_accuracy", kUsage);
  opts.positional("WORLD.stl", world_path)
      .positional("INPUT", input_path)
      .custom("--start",
              [&](const std::string& v) {
                parseRealListArg("--start", v, 3, -10000.0, 10000.0, "x,y,yaw");
                start_text = v;
              })
      .real("--tolerance", config.tolerance_m, 0.0, 1.0)
      .real("--sample", config.sample_spacing_m, 0.001, 1.0)
      .choice("--planes", planes_text, {"50", "100", "200", "400"})
      .real("--surface-cell", oracle.surface_cell_m, 0.01, 1.0)
      .real("--grid", oracle.grid_m, 0.05, 10.0)
      .flag("--no-coverage", no_coverage)
      .flag("--skip-bad", skip_bad)
      .flag("--json", json)
      .flag("--quiet", quiet);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  oracle.planes = std::stoi(planes_text);
  if (config.tolerance_m > oracle.surface_cell_m) {
    std::cerr << "surface_accuracy: --tolerance " << config.tolerance_m << " is larger than the surface cell "
              << oracle.surface_cell_m << "\n"
              << kUsage;
    return kExitUsage;
  }
  oracle.surface_tolerance_m = config.tolerance_m;
  try {
    const auto t0 = std::chrono::steady_clock::now();
    sim::SimConfig sim_config;  // the scanner of config/sim.yaml, perfect: the oracle's visible surface
    sim_config.errors = sim::makeProfile("perfect");
    Pose2D start;
    const std::unique_ptr<sim::Simulator> sim =
        sim::makeSimulator(world_path, sim::WorldOptions(), sim_config, start_text, "--start", &start);
    // The input before the long part, so that a bad one is named at once.
    const eval::AccuracyInput input = eval::loadAccuracyInput(input_path, skip_bad);
    const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const std::string& p : input.problems)
      std::cerr << "surface_accuracy: warning: " << p << "\n";  // also with --quiet: data was left out
    const eval::WorldSurfaceDistance world(sim->world().mesh());
    std::unique_ptr<eval::VisibleSurface> visible;
    double visible_s = 0.0;
    if (!no_coverage) {
      if (!quiet)
        std::cerr << "surface_accuracy: the visible surface (oracle scans, " << oracle.planes << " planes)...\n";
      visible = std::make_unique<eval::VisibleSurface>(eval::visibleSurface(*sim, start, oracle));
      visible_s = visible->seconds;
    }
    const eval::SurfaceAccuracy r = eval::measureSurfaceAccuracy(world, visible.get(), input, start, config);
    const bool mesh = input.kind == eval::AccuracyInput::Kind::Mesh;
    if (json) {
      std::cout << "{\"world\": " << jsonString(world_path) << ", \"input\": " << jsonString(input_path)
                << ", \"kind\": " << jsonString(eval::kindName(input.kind)) << ", \"start\": [" << jsonNumber(start.x)
                << ", " << jsonNumber(start.y) << ", " << jsonNumber(start.yaw) << "], \"scans\": " << input.scans
                << ", \"triangles\": " << r.triangles << ", \"vertices\": " << r.vertices
                << ", \"points\": " << r.points << ", \"samples\": " << r.samples
                << ", \"sample_m\": " << jsonNumber(config.sample_spacing_m)
                << ", \"area_m2\": " << jsonNumber(r.area_m2, 6) << ",\n \"distance\": " << statsJson(r.vertex_distance)
                << ",\n \"surface_distance\": " << statsJson(r.surface_distance) << ",\n \"coverage\": ";
      if (visible)
        std::cout << "{\"tolerance_m\": " << jsonNumber(config.tolerance_m)
                  << ", \"surface_cell_m\": " << jsonNumber(oracle.surface_cell_m) << ", \"planes\": " << oracle.planes
                  << ", \"visible\": " << r.visible << ", \"covered\": " << r.covered
                  << ", \"share\": " << jsonNumber(r.coverage, 6) << "}";
      else
        std::cout << "null";
      std::cout << ",\n \"time_s\": {\"load\": " << jsonNumber(load_s, 4)
                << ", \"visible\": " << jsonNumber(visible_s, 4) << ", \"distance\": " << jsonNumber(r.distance_s, 4)
                << ", \"coverage\": " << jsonNumber(r.coverage_s, 4) << "}}\n";
    } else {
      std::printf("surface_accuracy: %s (%s) against %s, map frame at (%g, %g, %g) in the world\n", input_path.c_str(),
                  eval::kindName(input.kind), world_path.c_str(), start.x, start.y, start.yaw);
      if (mesh) {
        std::printf("mesh: %zu triangles, %zu vertices, %.2f m2, %zu face samples every %g m\n", r.triangles,
                    r.vertices, r.area_m2, r.samples, config.sample_spacing_m);
        printStats("vertices to the world:", r.vertex_distance);
        printStats("surface (area-weighted):", r.surface_distance);
      } else {
        std::printf("points: %zu%s\n", r.points,
                    input.scans ? (" from " + std::to_string(input.scans) + " scans").c_str() : "");
        printStats("points to the world:", r.vertex_distance);
      }
      if (visible)
        std::printf("visible surface covered within %g m: %zu of %zu elements of %g m = %.2f %%\n", config.tolerance_m,
                    r.covered, r.visible, oracle.surface_cell_m, 100 * r.coverage);
      std::printf("time: load %.1f s, visible surface %.1f s, distances %.1f s, coverage %.1f s\n", load_s, visible_s,
                  r.distance_s, r.coverage_s);
    }
  } catch (const std::exception& e) {
    std::cerr << "surface_accuracy: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
