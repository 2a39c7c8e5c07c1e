/// fuse_map MAP_DIR OUTPUT [--voxel m] [--truncation m] [--carve m] [--carve-far] [--splat n] [--min-weight w]
///          [--threads n] [--mesh marching_cubes|points|bpa] [--decimate m] [--radii r1,...] [--vdb FILE] [--json]
///          [--skip-bad]
/// Integrates every scan of a map directory into the fused TSDF map (fused_map.h) and writes its
/// surface: Marching Cubes of the field, the fused surface points with normals, or Ball Pivoting of
/// those points.
#include <malloc.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/options.h"
#include "scanstop_mesher/decimate.h"
#include "scanstop_mesher/fused_map.h"
#include "scanstop_mesher/mesher.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

constexpr const char* kUsage =
    "usage: fuse_map MAP_DIR OUTPUT [--voxel m] [--truncation m] [--carve m] [--carve-far] [--splat n] [--min-weight "
    "w]\n"
    "                [--max-grid-mb MB] [--threads n] [--mesh marching_cubes|points|bpa] [--decimate m]\n"
    "                [--radii r1,r2,...] [--vdb FILE] [--json] [--skip-bad]\n"
    "  MAP_DIR       a map directory (poses.csv + scans/)\n"
    "  OUTPUT        .stl or .ply for a mesh; .ply, .pcd or .xyz for --mesh points; its directory must exist\n"
    "  --voxel       voxel edge [m], [0.001, 1] (default 0.02)\n"
    "  --truncation  half width of the signed-distance band around each reading [m], [2 voxels, 1]\n"
    "                (default 3 voxels: 0.06 at the default voxel)\n"
    "  --carve       free space carved before the band along each beam [m], [0, 1000]; 0 = none\n"
    "                (default 1000: the whole beam)\n"
    "  --carve-far   with --carve below 1000: carve the rest of each beam too, in a second pass over the\n"
    "                scans, in the voxels near some surface only (as the whole beam does there, cheaper)\n"
    "  --splat       lateral reach of each reading's band [voxels], [0, 3] (default 0: the crossed voxels;\n"
    "                1: 3 x 3 voxels across the beam, for beams up to 3 voxels apart, less accurate)\n"
    "  --min-weight  readings a voxel needs to count as seen, [1, 10000] (default 2)\n"
    "  --max-grid-mb bound on the fused grids' memory [MB], [1, 1e6] (default 500): a map whose grids would\n"
    "                need more as a whole is meshed in slabs along x (the same mesh; not with --mesh points or\n"
    "                --vdb: exit 1); one whose 1 m slabs do not fit either (a voxel too fine) ends at once, exit 1\n"
    "  --threads     threads integrating the scans, [1, 16] (default 2): each into grids of its own (within\n"
    "                --max-grid-mb / threads), merged\n"
    "  --mesh        marching_cubes (default): volumeToMesh of the field; points: the fused surface points\n"
    "                with normals; bpa: Ball Pivoting of those points\n"
    "  --decimate    decimate the Marching Cubes mesh within this error [m], [0, 0.1] (default 0.002, as\n"
    "                bpa_mesher_node; 0: none): quadric edge collapse, holes and outline kept\n"
    "  --radii       ball radii for --mesh bpa [m] (default: automatic from the point spacing)\n"
    "  --vdb         also write the fused grids (tsdf, weight) as an OpenVDB file\n"
    "  --json        print the result as one JSON object\n"
    "  --skip-bad    fuse the good scans of a map directory with bad scan files or lines (each named on\n"
    "                stderr); default: refuse such a map, naming the first problem\n"
    "exit status: 0 written, 2 bad arguments, 1 unreadable map or nothing to mesh\n";

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// A map too large for --max-grid-mb as a whole: meshed in slabs along x (meshFusedMapInSlabs), the
/// same mesh as the whole map's; prints the report. Returns the exit status.
int meshInSlabs(const std::string& map_dir, const std::string& output, const std::string& mode,
                const FusedMapConfig& config, const MesherConfig& bpa_config, const DecimateConfig& decimate,
                bool skip_bad, bool json) {
  std::vector<std::string> skipped;
  // Each slab's mesh decimated before the next is built: the memory of a slab, not of the whole mesh.
  FusedMesh r = meshFusedMapInSlabs(map_dir, config, mode == "bpa" ? "fused_bpa" : "marching_cubes", bpa_config,
                                    skip_bad ? &skipped : nullptr, 1.0, &decimate);
  for (const std::string& w : skipped) std::cerr << "fuse_map: warning: skipped: " << w << "\n";
  const DecimateStats& decimated = r.decimated;
  writeMesh(output, r.mesh);
  const MeshTopology t = analyzeTopology(r.mesh);
  if (json) {
    std::cout << "{\"map\": " << jsonString(map_dir) << ", \"output\": " << jsonString(output)
              << ", \"mesh\": " << jsonString(mode) << ", \"scans\": " << r.scans
              << ", \"voxel_m\": " << jsonNumber(config.voxel_m) << ", \"slabs\": " << r.slabs
              << ", \"scans_read\": " << r.scans_read << ", \"voxels\": " << r.voxels
              << ", \"memory_bytes\": " << r.memory_bytes << ", \"integrate_seconds\": " << jsonNumber(r.integrate_s)
              << ", \"mesh_seconds\": " << jsonNumber(r.mesh_s) << ", \"surface_points\": " << r.surface_points
              << ", \"decimated_from\": " << decimated.faces_before << ", \"triangles\": " << t.faces
              << ", \"vertices\": " << t.vertices << ", \"boundary_edges\": " << t.boundary_edges
              << ", \"nonmanifold_edges\": " << t.nonmanifold_edges
              << ", \"nonmanifold_vertices\": " << t.nonmanifold_vertices << ", \"components\": " << t.components << "}"
              << std::endl;
  } else {
    std::cout << "map:          " << map_dir << " (" << r.scans << " scans)\n"
              << "fused:        in " << r.slabs
              << " slabs along x (the whole map's grids would pass --max-grid-mb = " << config.max_grid_mb
              << " MB): " << r.voxels << " voxels, the largest slab " << r.memory_bytes / 1048576.0 << " MB; voxel "
              << config.voxel_m << " m\n"
              << "integration:  " << r.integrate_s << " s (" << r.scans_read
              << " scans read over the slabs: each reads those that reach it)\n"
              << "mesh:         " << mode << ", " << t.faces << " triangles, " << t.vertices << " vertices, "
              << t.boundary_edges << " boundary edges, " << t.nonmanifold_edges << " non-manifold edges\n";
    if (decimated.collapses > 0)
      std::cout << "decimated:    slab by slab, from " << decimated.faces_before << " triangles within "
                << decimate.max_error_m << " m in " << decimated.seconds << " s\n";
    std::cout << "meshing:      " << r.mesh_s << " s (with the decimation)\n"
              << "written:      " << output << std::endl;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_dir, output, mode = "marching_cubes", vdb;
  FusedMapConfig config;
  double truncation = -1.0;
  MesherConfig bpa_config;
  DecimateConfig decimate;
  bool json = false, skip_bad = false;
  Options opts("fuse_map", kUsage);
  opts.positional("MAP_DIR", map_dir)
      .positional("OUTPUT", output)
      .real("--voxel", config.voxel_m, 0.001, 1.0)
      .real("--truncation", truncation, 0.002, 1.0)
      .real("--carve", config.carve_m, 0.0, 1000.0)
      .flag("--carve-far", config.carve_far)
      .integer("--splat", config.splat, 0, 3)
      .real("--min-weight", config.min_weight, 1.0, 10000.0)
      .real("--max-grid-mb", config.max_grid_mb, 1.0, 1e6)
      .integer("--threads", config.threads, 1, 16)
      .choice("--mesh", mode, {"marching_cubes", "points", "bpa"})
      .real("--decimate", decimate.max_error_m, 0.0, 0.1)
      .custom("--radii", [&](const std::string& v) { bpa_config.radii_m = parseRadii(v); })
      .text("--vdb", vdb)
      .flag("--json", json)
      .flag("--skip-bad", skip_bad);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  const auto usage = [](const std::string& problem) {
    std::cerr << "fuse_map: " << problem << "\n" << kUsage;
    return kExitUsage;
  };
  config.truncation_m = truncation > 0 ? truncation : 3.0 * config.voxel_m;
  try {
    config.validate();
  } catch (const ConfigError& e) {
    return usage(std::string(e.what()) + (truncation > 0 ? " (--truncation)" : ""));
  }
  const std::string ext = fileExtension(output);
  if (mode == "points" ? (ext != "ply" && ext != "pcd" && ext != "xyz") : (ext != "stl" && ext != "ply"))
    return usage("OUTPUT " + output + ": --mesh " + mode + " writes " +
                 (mode == "points" ? ".ply, .pcd or .xyz" : ".stl or .ply"));
  if (!bpa_config.radii_m.empty() && mode != "bpa") return usage("--radii is only used with --mesh bpa");
  if (!vdb.empty() && fileExtension(vdb) != "vdb") return usage("--vdb " + vdb + ": must end in .vdb");
  try {
    for (const std::string& path : {output, vdb}) {  // before the work, not after it
      if (path.empty()) continue;
      const std::string problem = outputFileProblem(path);
      if (!problem.empty()) throw IoError(path, "cannot write: " + problem);
    }
    FusedMap fused(config);
    std::vector<std::string> skipped;
    size_t scans = 0;
    try {
      scans = integrateMapDirectory(fused, map_dir, skip_bad ? &skipped : nullptr);
    } catch (const GridBoundError& e) {
      // Too large for --max-grid-mb as a whole: a mesh is built in slabs along x (meshFusedMapInSlabs).
      if (mode == "points" || !vdb.empty())
        throw GridBoundError(std::string(e.what()) + "; in slabs along x only a mesh without --vdb is built");
      fused = FusedMap(config);  // the grids built so far are gone, their memory too
      malloc_trim(0);
      return meshInSlabs(map_dir, output, mode, config, bpa_config, decimate, skip_bad, json);
    }
    for (const std::string& w : skipped) std::cerr << "fuse_map: warning: skipped: " << w << "\n";
    const FusedMapStats& st = fused.stats();

    const auto t_mesh = std::chrono::steady_clock::now();
    size_t surface_points = 0;
    TriangleMesh mesh;
    DecimateStats decimated;
    if (mode == "marching_cubes") {
      mesh = fused.extractMesh();
      decimated = decimateMesh(mesh, decimate);
    } else {
      ScanPoints sp = fused.surfacePoints();
      surface_points = sp.size();
      if (mode == "points") {
        PointCloud cloud;
        cloud.points = std::move(sp.points);
        cloud.normals = std::move(sp.normals);
        cloud.setUnorganized();
        writeCloud(output, cloud);
      } else {
        mesh = buildMesh(sp, bpa_config).mesh;
      }
    }
    const double mesh_seconds = since(t_mesh);
    if (mode != "points") {
      if (mesh.faces.empty()) throw std::runtime_error("nothing to mesh: the fused map has no observed surface");
      writeMesh(output, mesh);
    }
    if (!vdb.empty()) fused.save(vdb);
    const MeshTopology t = mode == "points" ? MeshTopology() : analyzeTopology(mesh);

    if (json) {
      std::cout << "{\"map\": " << jsonString(map_dir) << ", \"output\": " << jsonString(output)
                << ", \"mesh\": " << jsonString(mode) << ", \"scans\": " << scans << ", \"points\": " << st.points
                << ", \"skipped_points\": " << st.skipped_points << ", \"voxel_m\": " << jsonNumber(config.voxel_m)
                << ", \"truncation_m\": " << jsonNumber(config.truncation_m)
                << ", \"carve_m\": " << jsonNumber(config.carve_m) << ", \"splat\": " << config.splat
                << ", \"slabs\": 1, \"voxels\": " << fused.activeVoxels()
                << ", \"observed_voxels\": " << fused.observedVoxels() << ", \"memory_bytes\": " << fused.memoryBytes()
                << ", \"voxel_updates\": " << st.voxel_updates
                << ", \"integrate_seconds\": " << jsonNumber(st.integrate_seconds)
                << ", \"mesh_seconds\": " << jsonNumber(mesh_seconds) << ", \"surface_points\": " << surface_points
                << ", \"decimated_from\": " << decimated.faces_before
                << ", \"decimate_seconds\": " << jsonNumber(decimated.seconds) << ", \"triangles\": " << t.faces
                << ", \"vertices\": " << t.vertices << ", \"boundary_edges\": " << t.boundary_edges
                << ", \"nonmanifold_edges\": " << t.nonmanifold_edges
                << ", \"nonmanifold_vertices\": " << t.nonmanifold_vertices << ", \"components\": " << t.components
                << "}" << std::endl;
    } else {
      std::cout << "map:          " << map_dir << " (" << scans << " scans, " << st.points << " readings, "
                << st.skipped_points << " skipped)\n"
                << "fused:        " << fused.activeVoxels() << " voxels (" << fused.observedVoxels()
                << " seen by >= " << config.min_weight << " readings), " << fused.memoryBytes() / 1048576.0
                << " MB; voxel " << config.voxel_m << " m, truncation " << config.truncation_m << " m, carve "
                << config.carve_m << " m, splat " << config.splat << "\n"
                << "integration:  " << st.integrate_seconds << " s (" << st.voxel_updates << " voxel updates)\n";
      if (mode != "marching_cubes") std::cout << "surface:      " << surface_points << " points with normals\n";
      if (mode != "points")
        std::cout << "mesh:         " << mode << ", " << t.faces << " triangles, " << t.vertices << " vertices, "
                  << t.components << " components, " << t.boundary_edges << " boundary edges, " << t.nonmanifold_edges
                  << " non-manifold edges, " << t.nonmanifold_vertices << " non-manifold vertices\n";
      if (decimated.collapses > 0)
        std::cout << "decimated:    from " << decimated.faces_before << " triangles within " << decimate.max_error_m
                  << " m in " << decimated.seconds << " s\n";
      std::cout << "meshing:      " << mesh_seconds << " s\n"
                << "written:      " << output << (vdb.empty() ? "" : " and " + vdb) << std::endl;
    }
    return 0;
  } catch (const ConfigError& e) {  // the voxel bound, found while integrating
    std::cerr << "fuse_map: " << e.what() << " (--voxel, --max-grid-mb)" << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "fuse_map: " << e.what() << std::endl;
    return 1;
  }
}
