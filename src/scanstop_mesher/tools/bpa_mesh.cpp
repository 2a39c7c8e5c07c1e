/// bpa_mesh INPUT OUTPUT [--radii r1,r2,...] [--voxel m] [--viewpoint x,y,z] [--no-smooth] [--json] [--skip-bad]
/// Ball Pivoting of a PLY/PCD/XYZ cloud (normals used as given; else estimated and turned towards
/// the viewpoint) or of a map directory (poses.csv + scans/), written as .stl (binary) or .ply.
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/options.h"
#include "scanstop_mesher/mesher.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

constexpr const char* kUsage =
    "usage: bpa_mesh INPUT OUTPUT [--radii r1,r2,...] [--voxel m] [--viewpoint x,y,z] [--no-smooth] [--json] "
    "[--skip-bad]\n"
    "  INPUT   .ply/.pcd/.xyz cloud, or a map directory (poses.csv + scans/)\n"
    "  OUTPUT  .stl (binary) or .ply (binary, with normals); its directory must exist\n"
    "  --radii      increasing ball radii [m] (default: automatic from the point spacing)\n"
    "  --voxel      voxel edge for downsampling [m], [0, 10] (default 0 = none)\n"
    "  --viewpoint  scanner position for clouds without normals [m], each within +-10000 (default 0,0,0)\n"
    "  --no-smooth  keep estimated-normal points where they are (default: moved onto their local plane)\n"
    "  --json       print the result as one JSON object\n"
    "  --skip-bad   mesh the good scans of a map directory with bad scan files or lines (each named on\n"
    "               stderr); default: refuse such a map, naming the first problem\n"
    "exit status: 0 meshed, 2 bad arguments, 1 unreadable input or nothing to mesh\n";

bool isDirectory(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output;
  MesherConfig config;
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  bool json = false, skip_bad = false, no_smooth = false;
  Options opts("bpa_mesh", kUsage);
  opts.positional("INPUT", input)
      .positional("OUTPUT", output)
      .custom("--radii", [&](const std::string& v) { config.radii_m = parseRadii(v); })
      .real("--voxel", config.voxel_m, 0.0, 10.0)
      .custom("--viewpoint",
              [&](const std::string& v) {
                const std::vector<double> p = parseRealListArg("--viewpoint", v, 3, -1e4, 1e4, "x,y,z");
                viewpoint = Eigen::Vector3d(p[0], p[1], p[2]).cast<float>();
              })
      .flag("--no-smooth", no_smooth)
      .flag("--json", json)
      .flag("--skip-bad", skip_bad);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  if (no_smooth) config.smooth = false;
  const auto usage = [](const std::string& problem) {
    std::cerr << "bpa_mesh: " << problem << "\n" << kUsage;
    return kExitUsage;
  };
  try {
    const std::string ext = fileExtension(output);
    if (ext != "stl" && ext != "ply") return usage("OUTPUT must end in .stl or .ply: " + output);
    const std::string out_problem = outputFileProblem(output);  // before the work, not after it
    if (!out_problem.empty()) throw IoError(output, "cannot write: " + out_problem);
    try {
      config.validate();
    } catch (const ConfigError& e) {
      return usage(e.what());
    }
    std::vector<std::string> skipped;
    const ScanPoints points = isDirectory(input) ? loadMapDirectory(input, skip_bad ? &skipped : nullptr)
                                                 : fromCloud(readCloud(input), viewpoint);
    for (const std::string& w : skipped) std::cerr << "bpa_mesh: warning: skipped: " << w << "\n";
    const MesherResult r = buildMesh(points, config);
    writeMesh(output, r.mesh);

    std::ostringstream radii;
    for (size_t k = 0; k < r.radii_m.size(); ++k) radii << (k ? "," : "") << r.radii_m[k];
    const MeshTopology& t = r.topology;
    if (json) {
      std::cout << "{\"input\": " << jsonString(input) << ", \"output\": " << jsonString(output)
                << ", \"input_points\": " << r.input_points << ", \"points\": " << r.points
                << ", \"used_points\": " << r.stats.used_points << ", \"triangles\": " << t.faces
                << ", \"nonmanifold_edges\": " << t.nonmanifold_edges
                << ", \"nonmanifold_vertices\": " << t.nonmanifold_vertices
                << ", \"inconsistent_edges\": " << t.inconsistent_edges << ", \"boundary_edges\": " << t.boundary_edges
                << ", \"components\": " << t.components << ", \"euler\": " << t.euler() << ", \"radii_m\": ["
                << radii.str() << "], \"spacing_m\": " << jsonNumber(r.spacing_m)
                << ", \"seconds\": " << jsonNumber(r.seconds) << ", \"bpa_seconds\": " << jsonNumber(r.bpa_seconds)
                << "}" << std::endl;
    } else {
      std::cout << "input:        " << input << " (" << r.input_points << " points)\n"
                << "meshed:       " << r.points << " points (spacing " << r.spacing_m << " m), radii " << radii.str()
                << " m\n"
                << "triangles:    " << t.faces << " (" << r.stats.used_points << " vertices, " << t.components
                << " components, Euler characteristic " << t.euler() << ")\n"
                << "non-manifold: " << t.nonmanifold_edges << " edges, " << t.nonmanifold_vertices << " vertices, "
                << t.inconsistent_edges << " inconsistently oriented edges; " << t.boundary_edges << " boundary edges\n"
                << "time:         " << r.seconds << " s (Ball Pivoting " << r.bpa_seconds << " s)\n"
                << "written:      " << output << std::endl;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "bpa_mesh: " << e.what() << std::endl;
    return 1;
  }
}
