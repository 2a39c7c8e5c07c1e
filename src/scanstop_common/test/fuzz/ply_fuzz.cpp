// libFuzzer target: arbitrary bytes through the PLY parser (ASCII and both binary encodings). The parser
// either throws IoError or returns a mesh whose faces index existing vertices.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using scanstop::fuzz::check;
  try {
    const scanstop::TriangleMesh mesh =
        scanstop::parsePly(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply");
    check(mesh.normals.empty() || mesh.normals.size() == mesh.vertices.size(), "one normal per vertex or none");
    for (const auto& f : mesh.faces)
      for (int k = 0; k < 3; ++k)
        check(f[k] >= 0 && f[k] < static_cast<int>(mesh.vertices.size()), "PLY faces index existing vertices");
  } catch (const scanstop::IoError& e) {
    check(std::string(e.what()).find("fuzz.ply") == 0, "the error names the file");
  }
  return 0;
}
