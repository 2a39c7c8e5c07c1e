/// decimate_mesh INPUT OUTPUT [--error m] [--max-faces n] [--json]
/// Decimates a triangle mesh (a run's mesh.ply, any .ply or .stl) by quadric edge collapse within a
/// bound on the geometric error (decimate.h); boundaries and holes stay as they are.
#include <iostream>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/options.h"
#include "scanstop_mesher/decimate.h"
#include "scanstop_mesher/mesh_analysis.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

constexpr const char* kUsage =
    "usage: decimate_mesh INPUT OUTPUT [--error m] [--max-faces n] [--json]\n"
    "  INPUT        a triangle mesh: .ply (indexed) or .stl\n"
    "  OUTPUT       .ply or .stl; its directory must exist\n"
    "  --error      bound on the distance of a merged vertex to the planes of the faces it replaces [m],\n"
    "               [0, 0.1] (default 0.002, as bpa_mesher_node); 0 copies the mesh\n"
    "  --max-faces  stop once the mesh has at most this many triangles (default 0: only the error bound)\n"
    "  --json       print the result as one JSON object\n"
    "exit status: 0 written, 2 bad arguments, 1 unreadable input or unwritable output\n";

}  // namespace

int main(int argc, char** argv) {
  std::string input, output;
  DecimateConfig config;
  bool json = false;
  Options opts("decimate_mesh", kUsage);
  opts.positional("INPUT", input)
      .positional("OUTPUT", output)
      .real("--error", config.max_error_m, 0.0, 0.1)
      .integer("--max-faces", config.max_faces, size_t{0}, size_t{1} << 40)
      .flag("--json", json);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  const std::string ext = fileExtension(output);
  if (ext != "ply" && ext != "stl") {
    std::cerr << "decimate_mesh: OUTPUT " << output << ": must end in .ply or .stl\n" << kUsage;
    return kExitUsage;
  }
  try {
    const std::string problem = outputFileProblem(output);
    if (!problem.empty()) throw IoError(output, "cannot write: " + problem);
    TriangleMesh mesh = readMesh(input);
    if (mesh.faces.empty()) throw IoError(input, "has no triangles");
    const DecimateStats s = decimateMesh(mesh, config);
    writeMesh(output, mesh);
    const MeshTopology t = analyzeTopology(mesh);
    if (json) {
      std::cout << "{\"input\": " << jsonString(input) << ", \"output\": " << jsonString(output)
                << ", \"error_bound_m\": " << jsonNumber(config.max_error_m) << ", \"faces_before\": " << s.faces_before
                << ", \"faces_after\": " << s.faces_after << ", \"vertices_before\": " << s.vertices_before
                << ", \"vertices_after\": " << s.vertices_after << ", \"collapses\": " << s.collapses
                << ", \"refused\": " << s.refused << ", \"locked_vertices\": " << s.locked_vertices
                << ", \"max_error_m\": " << jsonNumber(s.max_error_m) << ", \"seconds\": " << jsonNumber(s.seconds)
                << ", \"boundary_edges\": " << t.boundary_edges << ", \"nonmanifold_edges\": " << t.nonmanifold_edges
                << ", \"nonmanifold_vertices\": " << t.nonmanifold_vertices << "}" << std::endl;
    } else {
      std::cout << "input:        " << input << " (" << s.faces_before << " triangles, " << s.vertices_before
                << " vertices)\n"
                << "decimated:    " << s.faces_after << " triangles, " << s.vertices_after << " vertices ("
                << s.collapses << " collapses, " << s.refused << " refused, " << s.locked_vertices
                << " boundary vertices kept) in " << s.seconds << " s\n"
                << "error:        largest " << s.max_error_m << " m (bound " << config.max_error_m << " m)\n"
                << "topology:     " << t.boundary_edges << " boundary edges, " << t.nonmanifold_edges
                << " non-manifold edges, " << t.nonmanifold_vertices << " non-manifold vertices\n"
                << "written:      " << output << std::endl;
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "decimate_mesh: " << e.what() << std::endl;
    return 1;
  }
}
