/// bpa_mesh INPUT OUTPUT [--radii r1,r2,...] [--voxel m] [--viewpoint x,y,z] [--no-smooth] [--json]
/// Ball Pivoting of a PLY/PCD/XYZ cloud (normals used as given; else estimated and turned towards
/// the viewpoint) or of a map directory (poses.csv + scans/), written as .stl (binary) or .ply.
#include <sys/stat.h>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <sstream>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_mesher/mesher.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

int usage(const std::string& problem) {
  std::cerr << "bpa_mesh: " << problem << "\n"
            << "usage: bpa_mesh INPUT OUTPUT [--radii r1,r2,...] [--voxel m] [--viewpoint x,y,z] [--no-smooth] [--json]\n"
            << "  INPUT   .ply/.pcd/.xyz cloud, or a map directory (poses.csv + scans/)\n"
            << "  OUTPUT  .stl (binary) or .ply (binary, with normals)\n"
            << "  --radii      increasing ball radii [m] (default: automatic from the point spacing)\n"
            << "  --voxel      voxel edge for downsampling [m] (default 0 = none)\n"
            << "  --viewpoint  scanner position for clouds without normals [m] (default 0,0,0)\n"
            << "  --no-smooth  keep estimated-normal points where they are (default: moved onto their local plane)\n"
            << "  --json       print the result as one JSON object\n";
  return 2;
}

bool isDirectory(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output, radii_text;
  MesherConfig config;
  Eigen::Vector3f viewpoint = Eigen::Vector3f::Zero();
  bool json = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&](const char* name) -> std::string {
        if (i + 1 >= argc) throw ConfigError(std::string(name) + " needs a value");
        return argv[++i];
      };
      if (a == "--radii") {
        config.radii_m = parseRadii(value("--radii"));
      } else if (a == "--voxel") {
        const std::string v = value("--voxel");
        size_t used = 0;
        try {
          config.voxel_m = std::stod(v, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || used != v.size()) throw ConfigError("--voxel: '" + v + "' is not a number");
      } else if (a == "--viewpoint") {
        const std::string v = value("--viewpoint");
        float x, y, z;
        char tail;
        if (std::sscanf(v.c_str(), "%f,%f,%f%c", &x, &y, &z, &tail) != 3)
          throw ConfigError("--viewpoint: '" + v + "' is not x,y,z");
        viewpoint = Eigen::Vector3f(x, y, z);
      } else if (a == "--no-smooth") {
        config.smooth = false;
      } else if (a == "--json") {
        json = true;
      } else if (a == "-h" || a == "--help") {
        return usage("help");
      } else if (!a.empty() && a[0] == '-') {
        return usage("unknown option " + a);
      } else if (input.empty()) {
        input = a;
      } else if (output.empty()) {
        output = a;
      } else {
        return usage("too many arguments: " + a);
      }
    }
    if (output.empty()) return usage("INPUT and OUTPUT are required");
    const std::string ext = fileExtension(output);
    if (ext != "stl" && ext != "ply") return usage("OUTPUT must end in .stl or .ply: " + output);
    config.validate();

    const ScanPoints points = isDirectory(input) ? loadMapDirectory(input) : fromCloud(readCloud(input), viewpoint);
    const MesherResult r = buildMesh(points, config);
    writeMesh(output, r.mesh);

    std::ostringstream radii;
    for (size_t k = 0; k < r.radii_m.size(); ++k) radii << (k ? "," : "") << r.radii_m[k];
    const MeshTopology& t = r.topology;
    if (json) {
      std::cout << "{\"input\": \"" << input << "\", \"output\": \"" << output << "\", \"input_points\": "
                << r.input_points << ", \"points\": " << r.points << ", \"used_points\": " << r.stats.used_points
                << ", \"triangles\": " << t.faces << ", \"nonmanifold_edges\": " << t.nonmanifold_edges
                << ", \"nonmanifold_vertices\": " << t.nonmanifold_vertices
                << ", \"inconsistent_edges\": " << t.inconsistent_edges << ", \"boundary_edges\": " << t.boundary_edges
                << ", \"components\": " << t.components << ", \"euler\": " << t.euler() << ", \"radii_m\": [" << radii.str()
                << "], \"spacing_m\": " << r.spacing_m << ", \"seconds\": " << r.seconds
                << ", \"bpa_seconds\": " << r.bpa_seconds << "}" << std::endl;
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
  } catch (const ConfigError& e) {
    return usage(e.what());
  } catch (const std::exception& e) {
    std::cerr << "bpa_mesh: " << e.what() << std::endl;
    return 1;
  }
}
