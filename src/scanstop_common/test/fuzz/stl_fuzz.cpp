// libFuzzer target: arbitrary bytes through the STL parser (binary and ASCII). The parser either throws
// IoError or returns a triangle soup of finite vertices with valid faces.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.h"
#include "scanstop_common/error.h"
#include "scanstop_common/stl_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using scanstop::fuzz::check;
  try {
    const scanstop::TriangleMesh mesh =
        scanstop::parseStl(std::string(reinterpret_cast<const char*>(data), size), "fuzz.stl");
    check(!mesh.faces.empty(), "an STL that parses has triangles");
    check(mesh.vertices.size() == 3 * mesh.faces.size(), "an STL is a soup of three vertices per face");
    for (const auto& v : mesh.vertices) check(v.allFinite(), "STL vertices are finite");
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) check(mesh.faces[f][k] == static_cast<int>(3 * f + k), "STL face indices");
  } catch (const scanstop::IoError& e) {
    check(std::string(e.what()).find("fuzz.stl") == 0, "the error names the file");
  }
  return 0;
}
