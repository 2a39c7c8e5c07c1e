// fused_map_compare WORLD.stl MAP_DIR [--start x,y,yaw] [--voxel M] [--no-coverage] [--bt FILE] [--json] [--quiet]
// The fused map's measured comparison (issue #20 point 1: "OctoMap or a TSDF, chosen by a measured
// comparison"): the same scans at the same poses, in memory, integrated on one thread into
//   - OctoMap (liboctomap, Debian): occupancy with free-space carving along every beam, the library's
//     default sensor model (hit 0.7, miss 0.4, clamping 0.12 / 0.97); its surface: the centres of the
//     occupied leaves;
//   - our TSDF (scanstop_mesher's FusedMap with bpa_mesher_node's settings: 0.2 m carved before each
//     hit, the far pass over every beam); its surface: the fused surface points and the Marching
//     Cubes mesh;
// and each measured against the world (scanstop_eval's surface accuracy): distance to the true
// surfaces, stray points (more than 5 cm off: readings that later scans contradict and that stayed),
// the share of the visible surface covered within 3 cm, build time and memory.
#include <octomap/OcTree.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/options.h"
#include "scanstop_common/robot_body.h"
#include "scanstop_eval/surface_accuracy.h"
#include "scanstop_explorer/parameters.h"
#include "scanstop_mesher/fused_map.h"
#include "scanstop_sim/simulator.h"

namespace {

constexpr const char* kUsage =
    "usage: fused_map_compare WORLD.stl MAP_DIR [--start x,y,yaw] [--voxel M] [--no-coverage] [--bt FILE] [--json]\n"
    "                         [--quiet]\n"
    "  WORLD.stl      the simulated world the map was made in\n"
    "  MAP_DIR        a map directory (poses.csv and its scans; every scan at its map pose)\n"
    "  --start        the simulated start pose in the world = the map frame's pose [m, m, rad] (default: the\n"
    "                 world's documented start pose, as sim_node)\n"
    "  --voxel        voxel of both maps [m], [0.005, 0.5] (default 0.02, bpa_mesher_node's fused_voxel_m)\n"
    "  --no-coverage  distances only: no visible surface (no simulated scans)\n"
    "  --bt FILE      also write the OctoMap (.bt, for octovis)\n"
    "  --json         one JSON object on stdout instead of the table\n"
    "  --quiet        no progress on stderr\n"
    "exit status: 0 done, 2 bad arguments, 1 unreadable world or map\n";

using namespace scanstop;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Scan {
  std::vector<Eigen::Vector3f> points;  ///< map frame, finite
  Eigen::Vector3f origin;               ///< sensor origin, map frame
};

struct Row {
  std::string name;
  double build_s = 0.0, surface_s = 0.0;
  double memory_mb = 0.0;
  size_t elements = 0;  ///< leaves or voxels
  eval::SurfaceAccuracy accuracy;
  bool mesh = false;
};

size_t stray(const eval::DistanceStats& d) {  // beyond the last threshold (5 cm)
  return d.share.empty() ? 0 : static_cast<size_t>(std::llround(d.count * (1.0 - d.share.back())));
}

}  // namespace

int main(int argc, char** argv) {
  std::string world_path, map_dir, start_text, bt_path;
  double voxel = 0.02;
  bool json = false, quiet = false, no_coverage = false;
  Options opts("fused_map_compare", kUsage);
  opts.positional("WORLD.stl", world_path)
      .positional("MAP_DIR", map_dir)
      .custom("--start",
              [&](const std::string& v) {
                parseRealListArg("--start", v, 3, -10000.0, 10000.0, "x,y,yaw");
                start_text = v;
              })
      .real("--voxel", voxel, 0.005, 0.5)
      .flag("--no-coverage", no_coverage)
      .text("--bt", bt_path)
      .flag("--json", json)
      .flag("--quiet", quiet);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  if (!bt_path.empty() && fileExtension(bt_path) != "bt") {
    std::cerr << "fused_map_compare: --bt " << bt_path << ": must end in .bt\n" << kUsage;
    return kExitUsage;
  }
  const auto say = [&](const std::string& s) {
    if (!quiet) std::cerr << "fused_map_compare: " << s << std::endl;
  };
  try {
    sim::SimConfig sim_config;  // the scanner of config/sim.yaml, perfect: the oracle's visible surface
    sim_config.errors = sim::makeProfile("perfect");
    Pose2D start;
    const std::unique_ptr<sim::Simulator> sim =
        sim::makeSimulator(world_path, sim::WorldOptions(), sim_config, start_text, "--start", &start);
    const MapDirectory map =
        openMapForTool(map_dir, false, [](const std::string& w) { std::cerr << "fused_map_compare: " << w << "\n"; });
    std::vector<Scan> scans(map.size());
    size_t readings = 0;
    for (size_t s = 0; s < map.size(); ++s) {
      const MapScanInfo& info = map.scans()[s];
      const PointCloud cloud = map.loadScan(s);
      const Eigen::Isometry3f T = info.map_pose.toIsometry3f();
      for (const Eigen::Vector3f& p : cloud.points)
        if (p.allFinite()) scans[s].points.push_back(T * p);
      scans[s].origin = T * info.sensor_origin.cast<float>();
      readings += scans[s].points.size();
    }
    say(std::to_string(scans.size()) + " scans, " + std::to_string(readings) + " readings loaded");

    const eval::WorldSurfaceDistance world(sim->world().mesh());
    std::unique_ptr<eval::VisibleSurface> visible;
    if (!no_coverage) {
      say("the visible surface (oracle scans, 400 planes)...");
      eval::OracleConfig oracle;
      oracle.robot_radius_m = RobotBody().radius_m + explorer::BodyMargins().inflation_margin_m;
      oracle.z_hi_m = RobotBody().height_m + explorer::BodyMargins().obstacle_height_margin_m;
      visible = std::make_unique<eval::VisibleSurface>(eval::visibleSurface(*sim, start, oracle));
    }
    const auto measure = [&](eval::AccuracyInput input) {
      return eval::measureSurfaceAccuracy(world, visible.get(), input, start);
    };
    std::vector<Row> rows;

    {  // OctoMap
      say("OctoMap...");
      Row row;
      row.name = "OctoMap (occupied leaves)";
      auto t0 = Clock::now();
      octomap::OcTree tree(voxel);
      for (const Scan& scan : scans) {
        octomap::Pointcloud cloud;
        cloud.reserve(scan.points.size());
        for (const Eigen::Vector3f& p : scan.points) cloud.push_back(p.x(), p.y(), p.z());
        tree.insertPointCloud(cloud, octomap::point3d(scan.origin.x(), scan.origin.y(), scan.origin.z()));
      }
      row.build_s = since(t0);
      row.memory_mb = tree.memoryUsage() / 1048576.0;
      row.elements = tree.getNumLeafNodes();
      t0 = Clock::now();
      eval::AccuracyInput input;
      input.kind = eval::AccuracyInput::Kind::Cloud;
      for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it)
        if (tree.isNodeOccupied(*it)) {
          const octomap::point3d c = it.getCoordinate();
          input.points.emplace_back(c.x(), c.y(), c.z());
        }
      row.surface_s = since(t0);
      row.accuracy = measure(std::move(input));
      rows.push_back(row);
      if (!bt_path.empty() && !tree.writeBinary(bt_path)) throw IoError(bt_path, "cannot write the OctoMap");
    }

    {  // our TSDF, bpa_mesher_node's settings
      say("TSDF...");
      mesher::FusedMapConfig config;
      config.voxel_m = voxel;
      config.truncation_m = 3.0 * voxel;
      config.carve_m = 0.2;
      config.carve_far = true;
      config.max_grid_mb = 8000.0;
      config.threads = 1;
      auto t0 = Clock::now();
      mesher::FusedMap fused(config);
      for (const Scan& scan : scans) fused.integrate(scan.points, scan.origin);
      fused.carveFarAll(
          scans.size(),
          [&](size_t s, std::vector<Eigen::Vector3f>& points, Eigen::Vector3f& origin) {
            points = scans[s].points;
            origin = scans[s].origin;
            return true;
          },
          1);
      const double build_s = since(t0);
      Row points_row;
      points_row.name = "TSDF (fused surface points)";
      points_row.build_s = build_s;
      points_row.memory_mb = fused.memoryBytes() / 1048576.0;
      points_row.elements = fused.activeVoxels();
      Row mesh_row = points_row;
      mesh_row.name = "TSDF (Marching Cubes mesh)";
      mesh_row.mesh = true;
      t0 = Clock::now();
      eval::AccuracyInput input;
      input.kind = eval::AccuracyInput::Kind::Cloud;
      input.points = fused.surfacePoints().points;
      points_row.surface_s = since(t0);
      points_row.accuracy = measure(std::move(input));
      t0 = Clock::now();
      eval::AccuracyInput mesh;
      mesh.kind = eval::AccuracyInput::Kind::Mesh;
      mesh.mesh = fused.extractMesh();
      mesh_row.surface_s = since(t0);
      mesh_row.accuracy = measure(std::move(mesh));
      rows.push_back(points_row);
      rows.push_back(mesh_row);
    }

    if (json) {
      std::cout << "{\"world\": " << jsonString(world_path) << ", \"map\": " << jsonString(map_dir)
                << ", \"scans\": " << scans.size() << ", \"readings\": " << readings
                << ", \"voxel_m\": " << jsonNumber(voxel) << ", \"methods\": [";
      for (size_t i = 0; i < rows.size(); ++i) {
        const Row& r = rows[i];
        const eval::DistanceStats& d = r.accuracy.vertex_distance;
        std::cout << (i ? ",\n  " : "\n  ") << "{\"name\": " << jsonString(r.name)
                  << ", \"build_s\": " << jsonNumber(r.build_s, 4) << ", \"surface_s\": " << jsonNumber(r.surface_s, 4)
                  << ", \"memory_mb\": " << jsonNumber(r.memory_mb, 4) << ", \"elements\": " << r.elements
                  << ", \"points\": " << d.count << ", \"triangles\": " << r.accuracy.triangles
                  << ", \"median_m\": " << jsonNumber(d.median_m, 6) << ", \"rms_m\": " << jsonNumber(d.rms_m, 6)
                  << ", \"p95_m\": " << jsonNumber(d.p95_m, 6) << ", \"stray\": " << stray(d)
                  << ", \"coverage\": " << (visible ? jsonNumber(r.accuracy.coverage, 6) : std::string("null")) << "}";
      }
      std::cout << "]}\n";
    } else {
      std::printf("map %s: %zu scans, %zu readings; voxel %.3f m; one thread each, scans in memory\n", map_dir.c_str(),
                  scans.size(), readings, voxel);
      std::printf("%-28s %9s %9s %11s %10s %22s %8s %8s\n", "method", "build [s]", "mem [MB]", "leaves/vox", "points",
                  "median/RMS/p95 [mm]", "> 5 cm", "covered");
      for (const Row& r : rows) {
        const eval::DistanceStats& d = r.accuracy.vertex_distance;
        char dist[64], cov[16];
        std::snprintf(dist, sizeof dist, "%.1f / %.1f / %.1f", 1e3 * d.median_m, 1e3 * d.rms_m, 1e3 * d.p95_m);
        if (visible)
          std::snprintf(cov, sizeof cov, "%.1f %%", 100.0 * r.accuracy.coverage);
        else
          std::snprintf(cov, sizeof cov, "-");
        std::printf("%-28s %9.2f %9.1f %11zu %10zu %22s %8zu %8s\n", r.name.c_str(), r.build_s, r.memory_mb, r.elements,
                    d.count, dist, stray(d), cov);
      }
      std::printf(
          "(distances of the points; the mesh: of its vertices; > 5 cm: points that far from every true surface;\n"
          " covered: the visible surface within 3 cm; the TSDF rows share one build)\n");
    }
  } catch (const std::exception& e) {
    std::cerr << "fused_map_compare: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
