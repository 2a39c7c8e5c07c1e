// coverage_oracle WORLD.stl [--start x,y,yaw] [--grid M] [--planes N] [--json] [...]
// A known-map reference for exploration (issue #19): candidate poses every M metres on the truly
// reachable floor, one simulated perfect scan at each, and a greedy set cover (pairs checked
// exactly): how many scans see 90 / 95 / 99 % of the reachable floor and of the visible surface.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/options.h"
#include "scanstop_common/robot_body.h"
#include "scanstop_eval/coverage_oracle.h"
#include "scanstop_explorer/parameters.h"

namespace {

constexpr const char* kUsage =
    "usage: coverage_oracle WORLD.stl [--start x,y,yaw] [--grid M] [--planes 50|100|200|400] [--json] [options]\n"
    "  WORLD.stl      the simulated world (sim_node's ~world)\n"
    "  --start        the robot's start pose in the world [m, m, rad], |x|, |y| <= 10000; the reachable floor is\n"
    "                 what the robot reaches from there (default: the world's documented start pose, as sim_node)\n"
    "  --grid         candidate spacing [m], [0.05, 10] (default 0.5; a lattice through the start)\n"
    "  --planes       planes of each candidate's scan (default 400)\n"
    "  --profile      the scans' error profile, perfect or thesis (default perfect)\n"
    "  --radius       robot disc of the reachable floor and of the candidates [m], [0.001, 5] (default 0.3:\n"
    "                 robot_body/radius 0.26 + the explorer's inflation_margin_m 0.04)\n"
    "  --cell         floor cell [m], [0.01, 1], a whole multiple of --raster (default 0.1)\n"
    "  --raster       raster of the true reachable floor, as floor_coverage's [m], [0.01, 1] (default 0.05)\n"
    "  --floor-tolerance  a floor cell is seen when a floor hit lies this close to it (its square) [m], [0, 1]\n"
    "                 (default 0.1)\n"
    "  --known-free   floor cells this close to a scan's pose count as seen (the explorer's known_free_radius_m:\n"
    "                 the cone below the scanner) [m], [0, 5] (default 0.8; 0: floor hits only)\n"
    "  --surface-cell surface element size [m], [0.01, 1] (default 0.05)\n"
    "  --surface-tolerance  an element is seen when a hit lies this close to it [m], [0, surface cell] (default 0.03)\n"
    "  --json         one JSON object on stdout instead of the text report\n"
    "  --quiet        no progress on stderr\n"
    "exit status: 0 done, 2 bad arguments, 1 unreadable world or a start where the robot cannot stand\n";

using scanstop::jsonNumber;
using scanstop::eval::CoverResult;
using scanstop::eval::OracleResult;

std::string scansText(const scanstop::eval::CoverTarget& t) {
  if (!t.scans) return "never";
  return std::to_string(*t.scans) + (t.optimal ? "" : " (greedy)");
}

std::string coverJson(const CoverResult& c, const std::vector<Eigen::Vector2d>& candidates) {
  std::ostringstream o;
  o << "{\"total\": " << c.total << ", \"scans\": {";
  for (size_t i = 0; i < c.targets.size(); ++i)
    o << (i ? ", " : "") << "\"" << static_cast<int>(c.targets[i].share * 100 + 0.5)
      << "\": " << (c.targets[i].scans ? std::to_string(*c.targets[i].scans) : "null");
  o << "}, \"optimal\": {";
  for (size_t i = 0; i < c.targets.size(); ++i)
    o << (i ? ", " : "") << "\"" << static_cast<int>(c.targets[i].share * 100 + 0.5)
      << "\": " << (c.targets[i].optimal ? "true" : "false");
  o << "}, \"best_pair\": " << (c.best_pair ? std::to_string(*c.best_pair) : "null") << ", \"curve\": [";
  for (size_t k = 1; k <= c.greedy.covered.size(); ++k) o << (k > 1 ? ", " : "") << jsonNumber(c.shareAfter(k), 6);
  o << "], \"poses\": [";
  for (size_t k = 0; k < c.greedy.order.size(); ++k) {
    const Eigen::Vector2d& p = candidates[c.greedy.order[k]];
    o << (k ? ", " : "") << "[" << jsonNumber(p.x(), 6) << ", " << jsonNumber(p.y(), 6) << "]";
  }
  o << "]}";
  return o.str();
}

void printJson(const std::string& world, const OracleResult& r, const scanstop::eval::OracleConfig& c) {
  const double floor_share = r.floor_cells ? static_cast<double>(r.floor_seen) / r.floor_cells : 0.0;
  const double completeness = r.surface_elements ? static_cast<double>(r.surface_visible) / r.surface_elements : 0.0;
  std::cout << "{\"world\": " << scanstop::jsonString(world) << ", \"start\": [" << jsonNumber(r.start.x) << ", "
            << jsonNumber(r.start.y) << ", " << jsonNumber(r.start.yaw) << "], \"grid_m\": " << jsonNumber(c.grid_m)
            << ", \"planes\": " << c.planes << ", \"radius_m\": " << jsonNumber(c.robot_radius_m)
            << ", \"cell_m\": " << jsonNumber(c.cell_m) << ", \"raster_m\": " << jsonNumber(c.raster_m)
            << ", \"known_free_m\": " << jsonNumber(c.known_free_m) << ", \"candidates\": " << r.candidates.size()
            << ", \"candidates_refused\": " << r.candidates_refused
            << ", \"reachable_m2\": " << jsonNumber(r.reachable_m2, 6) << ", \"floor_cells\": " << r.floor_cells
            << ", \"floor_seen_share\": " << jsonNumber(floor_share, 6)
            << ", \"surface_elements\": " << r.surface_elements << ", \"surface_visible\": " << r.surface_visible
            << ", \"surface_completeness\": " << jsonNumber(completeness, 6)
            << ",\n \"floor\": " << coverJson(r.floor, r.candidates)
            << ",\n \"surface\": " << coverJson(r.surface, r.candidates)
            << ",\n \"time_s\": {\"setup\": " << jsonNumber(r.setup_s, 4) << ", \"scans\": " << jsonNumber(r.scan_s, 4)
            << ", \"cover\": " << jsonNumber(r.cover_s, 4) << "}}\n";
}

void printText(const std::string& world, const OracleResult& r, const scanstop::eval::OracleConfig& c) {
  std::printf(
      "coverage_oracle: %s from (%g, %g, %g): %zu candidates every %g m (%zu refused by the simulator), %d planes\n",
      world.c_str(), r.start.x, r.start.y, r.start.yaw, r.candidates.size(), c.grid_m, r.candidates_refused, c.planes);
  std::printf("reachable floor: %.1f m2 (raster %g m) in %zu cells of %g m, seen by some candidate: %.1f %%\n",
              r.reachable_m2, c.raster_m, r.floor_cells, c.cell_m,
              r.floor_cells ? 100.0 * r.floor_seen / r.floor_cells : 0.0);
  std::printf("surface: %zu elements of %g m, visible from the reachable floor: %zu (surface completeness %.1f %%)\n",
              r.surface_elements, c.surface_cell_m, r.surface_visible,
              r.surface_elements ? 100.0 * r.surface_visible / r.surface_elements : 0.0);
  std::printf("scans needed (greedy set cover, pairs checked exactly; \"(greedy)\": fewer may do):\n");
  for (const auto* cover : {&r.floor, &r.surface}) {
    std::printf("  %-8s", cover == &r.floor ? "floor" : "surface");
    for (const auto& t : cover->targets) std::printf("  %g %%: %s", t.share * 100, scansText(t).c_str());
    std::printf("\n");
  }
  std::printf("coverage after k scans (floor cover: floor %% | surface cover: visible surface %%):\n");
  const size_t n = std::max(r.floor.greedy.covered.size(), r.surface.greedy.covered.size());
  for (size_t k = 1; k <= n; ++k)
    std::printf("  %3zu: %6.2f %% | %6.2f %%\n", k, 100 * r.floor.shareAfter(k), 100 * r.surface.shareAfter(k));
  std::printf("floor cover poses (x, y) [m]:");
  for (const size_t i : r.floor.greedy.order) std::printf(" (%.2f, %.2f)", r.candidates[i].x(), r.candidates[i].y());
  std::printf("\ntime: %.1f s (setup %.1f s, scans %.1f s, cover %.1f s)\n", r.setup_s + r.scan_s + r.cover_s,
              r.setup_s, r.scan_s, r.cover_s);
}

/// What is wrong with options that depend on each other ("" when nothing).
std::string optionProblem(const scanstop::eval::OracleConfig& c) {
  std::ostringstream o;
  if (c.surface_tolerance_m > c.surface_cell_m)
    o << "--surface-tolerance " << c.surface_tolerance_m << " is larger than the surface cell " << c.surface_cell_m;
  else if (c.cell_m < c.raster_m || std::abs(c.cellsPerFloorCell() * c.raster_m - c.cell_m) > 1e-6 * c.cell_m)
    o << "--cell " << c.cell_m << " is not a whole multiple of --raster " << c.raster_m;
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace scanstop;
  std::string world_path, start_text, profile = "perfect", planes_text = "400";
  bool json = false, quiet = false;
  eval::OracleConfig config;
  config.robot_radius_m = RobotBody().radius_m + explorer::BodyMargins().inflation_margin_m;
  config.z_hi_m = RobotBody().height_m + explorer::BodyMargins().obstacle_height_margin_m;
  Options opts("coverage_oracle", kUsage);
  opts.positional("WORLD.stl", world_path)
      .custom("--start",
              [&](const std::string& v) {
                parseRealListArg("--start", v, 3, -10000.0, 10000.0, "x,y,yaw");
                start_text = v;
              })
      .real("--grid", config.grid_m, 0.05, 10.0)
      .choice("--planes", planes_text, {"50", "100", "200", "400"})
      .choice("--profile", profile, {"perfect", "thesis"})
      .real("--radius", config.robot_radius_m, 1e-3, 5.0)
      .real("--cell", config.cell_m, 0.01, 1.0)
      .real("--raster", config.raster_m, 0.01, 1.0)
      .real("--floor-tolerance", config.floor_tolerance_m, 0.0, 1.0)
      .real("--known-free", config.known_free_m, 0.0, 5.0)
      .real("--surface-cell", config.surface_cell_m, 0.01, 1.0)
      .real("--surface-tolerance", config.surface_tolerance_m, 0.0, 1.0)
      .flag("--json", json)
      .flag("--quiet", quiet);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  config.planes = std::stoi(planes_text);
  if (const std::string problem = optionProblem(config); !problem.empty()) {
    std::cerr << "coverage_oracle: " << problem << "\n" << kUsage;
    return kExitUsage;
  }
  try {
    sim::SimConfig sim_config;  // the scanner of config/sim.yaml (a test keeps the defaults equal)
    sim_config.errors = sim::makeProfile(profile);
    Pose2D start;
    const std::unique_ptr<sim::Simulator> sim =
        sim::makeSimulator(world_path, sim::WorldOptions(), sim_config, start_text, "--start", &start);
    size_t last_tenth = 0;
    const auto progress = [&](size_t done, size_t total) {
      if (quiet || done * 10 / total == last_tenth) return;
      last_tenth = done * 10 / total;
      std::cerr << "coverage_oracle: " << done << " of " << total << " candidates scanned\n";
    };
    const eval::OracleResult r = eval::runCoverageOracle(*sim, start, config, progress);
    if (json)
      printJson(world_path, r, config);
    else
      printText(world_path, r, config);
  } catch (const std::exception& e) {
    std::cerr << "coverage_oracle: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
