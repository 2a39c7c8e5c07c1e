// bpa_bench: timing of our Ball Pivoting, and the helpers the peer comparison (run_bench.sh) needs.
//   bpa_bench bunny [--ply BUNNY.ply] [--points-out POINTS.ply] [--repeat N]
//       the Stanford bunny's reference vertices with normals from its faces, one radius and three
//       radii: best time of N runs, triangles, non-manifold edges/vertices, mean distance
//   bpa_bench analyze MESH.(ply|stl) [REFERENCE.ply]
//       triangles and non-manifold counts of a mesh (a peer's output); distance to a reference
//   bpa_bench make_map MAP_DIR LIST.txt
//       appends scans to a map directory; LIST lines: "scan.pcd x y yaw" (base_link, map pose)
//   bpa_bench map MAP_DIR [--voxel m] [--out MESH.ply]
//       meshes a map directory (automatic radii) and prints time and counts
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/shared_data.h"
#include "scanstop_mesher/ball_pivoting.h"
#include "scanstop_mesher/mesh_analysis.h"
#include "scanstop_mesher/mesher.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

void printRow(const std::string& name, double seconds, const TriangleMesh& mesh, const TriangleMesh* reference) {
  const MeshTopology t = analyzeTopology(mesh);
  std::printf("%-34s %9.3f s %9zu triangles %6zu nm-edges %6zu nm-vertices", name.c_str(), seconds, t.faces,
              t.nonmanifold_edges, t.nonmanifold_vertices);
  if (reference) std::printf(" %8.4f mm mean dist", distanceToSurface(sampleFaces(mesh), *reference).mean_m * 1e3);
  std::printf("\n");
}

int bunny(int argc, char** argv) {
  std::string ply = sharedDataPath("bunny/bun_zipper.ply"), points_out;
  int repeat = 5;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--ply")
      ply = argv[i + 1];
    else if (a == "--points-out")
      points_out = argv[i + 1];
    else if (a == "--repeat")
      repeat = std::max(1, std::atoi(argv[i + 1]));
    else
      throw ConfigError("unknown option " + a);
  }
  const TriangleMesh ref = readPly(ply);
  const std::vector<Eigen::Vector3f> normals = vertexNormalsFromFaces(ref);
  if (!points_out.empty()) {
    PointCloud cloud;
    cloud.points = ref.vertices;
    cloud.normals = normals;
    cloud.setUnorganized();
    writePlyCloud(points_out, cloud, false);
  }
  std::printf("Stanford bunny: %zu points with normals from the reference faces (%zu reference triangles)\n",
              ref.vertices.size(), ref.faces.size());
  const std::vector<std::vector<double>> sets = {{0.0012}, {0.0012, 0.0024, 0.0048}};
  for (const auto& radii : sets) {
    double best = 1e9;
    TriangleMesh mesh;
    for (int k = 0; k < repeat; ++k) {
      const double t0 = now();
      BallPivoting bpa(ref.vertices, normals);
      for (double r : radii) bpa.pivot(r);
      mesh = bpa.mesh();
      best = std::min(best, now() - t0);
    }
    std::ostringstream name;
    name << "ours radii";
    for (double r : radii) name << " " << r;
    printRow(name.str(), best, mesh, &ref);
  }
  return 0;
}

int analyze(int argc, char** argv) {
  if (argc < 3) throw ConfigError("analyze needs a mesh file");
  const TriangleMesh mesh = readMesh(argv[2]);
  TriangleMesh ref;
  if (argc > 3) ref = readPly(argv[3]);
  const MeshTopology t = analyzeTopology(mesh);
  std::printf("triangles %zu nm_edges %zu nm_vertices %zu", t.faces, t.nonmanifold_edges, t.nonmanifold_vertices);
  if (argc > 3) std::printf(" mean_dist_mm %.4f", distanceToSurface(sampleFaces(mesh), ref).mean_m * 1e3);
  std::printf("\n");
  return 0;
}

int makeMap(int argc, char** argv) {
  if (argc < 4) throw ConfigError("make_map needs MAP_DIR LIST.txt");
  MapDirectory map(argv[2]);
  std::ifstream list(argv[3]);
  if (!list) throw IoError(argv[3], "cannot read");
  std::string line;
  int lineno = 0;
  while (std::getline(list, line)) {
    ++lineno;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string pcd;
    double x, y, yaw, z_sensor;
    if (!(in >> pcd >> x >> y >> yaw >> z_sensor))
      throw IoError(argv[3], "line " + std::to_string(lineno) + ": expected 'scan.pcd x y yaw sensor_z'");
    MapScanInfo info;
    info.index = static_cast<uint32_t>(map.size());
    info.map_pose = info.odom_pose = Pose2D(x, y, yaw);
    info.sensor_origin = Eigen::Vector3d(0, 0, z_sensor);
    map.append(info, removeNonFinite(readCloud(pcd)));
  }
  std::printf("map %s: %zu scans\n", argv[2], map.size());
  return 0;
}

int meshMap(int argc, char** argv) {
  if (argc < 3) throw ConfigError("map needs MAP_DIR");
  MesherConfig config;
  config.voxel_m = 0.01;
  std::string out;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--voxel")
      config.voxel_m = std::stod(argv[i + 1]);
    else if (a == "--out")
      out = argv[i + 1];
    else if (a == "--smooth")
      config.smooth = std::string(argv[i + 1]) == "1";
    else if (a == "--normal-radius")
      config.normal_radius_m = std::stod(argv[i + 1]);
    else if (a == "--radii")
      config.radii_m = parseRadii(argv[i + 1]);
    else
      throw ConfigError("unknown option " + a);
  }
  const double t0 = now();
  const ScanPoints pts = loadMapDirectory(argv[2]);
  const double t_load = now() - t0;
  const MesherResult r = buildMesh(pts, config);
  std::printf("map %s: %zu points (load %.2f s), voxel %.3f m -> %zu points meshed, radii", argv[2], r.input_points,
              t_load, config.voxel_m, r.points);
  for (double x : r.radii_m) std::printf(" %.4f", x);
  std::printf(" m\n");
  printRow("ours (voxels, normals, BPA)", r.seconds, r.mesh, nullptr);
  std::printf("%-34s %9.3f s\n", "  voxels, spacing, normals", r.prepare_seconds);
  std::printf("%-34s %9.3f s (triangles after each radius:", "  Ball Pivoting", r.bpa_seconds);
  for (size_t n : r.stats.triangles_per_radius) std::printf(" %zu", n);
  std::printf("; %zu seeds, %zu pivots, %zu pinches, %zu triangles dropped; seconds per radius:", r.stats.seeds,
              r.stats.pivots, r.stats.pinches, r.stats.dropped_triangles);
  for (double s : r.stats.seconds_per_radius) std::printf(" %.2f", s);
  std::printf(")\n");
  if (r.stats.regions > 1)
    std::printf("%-34s %9.3f s in %d slabs in parallel, %.3f s merge and seams, %.3f s mesh\n", "  of which",
                r.stats.region_seconds, r.stats.regions, r.stats.seam_seconds, r.stats.mesh_seconds);
  if (!out.empty()) writeMesh(out, r.mesh);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string cmd = argc > 1 ? argv[1] : "bunny";
    if (cmd == "bunny") return bunny(argc, argv);
    if (cmd == "analyze") return analyze(argc, argv);
    if (cmd == "make_map") return makeMap(argc, argv);
    if (cmd == "map") return meshMap(argc, argv);
    std::cerr << "bpa_bench: unknown command " << cmd << " (bunny, analyze, make_map, map)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "bpa_bench: " << e.what() << std::endl;
    return 1;
  }
}
