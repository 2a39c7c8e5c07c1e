#pragma once
/// STL (stereolithography) triangle files, binary and ASCII.

#include <string>

#include "scanstop_common/cloud.h"

namespace scanstop {

/// Reads a binary or ASCII STL file (detected from the content) as a triangle soup: three
/// vertices per face, vertex i*3+k is corner k of face i. Throws IoError naming the file and the
/// problem: missing, empty, truncated, triangle count not matching the size, non-finite
/// coordinates, malformed ASCII, or not an STL at all.
TriangleMesh readStl(const std::string& path);

/// Parses STL content held in memory; `name` is used in error messages.
TriangleMesh parseStl(const std::string& data, const std::string& name);

/// Writes a binary STL (face normals from the winding). Atomic; throws IoError.
void writeStlBinary(const std::string& path, const TriangleMesh& mesh);

/// Writes an ASCII STL. Atomic; throws IoError.
void writeStlAscii(const std::string& path, const TriangleMesh& mesh);

}  // namespace scanstop
