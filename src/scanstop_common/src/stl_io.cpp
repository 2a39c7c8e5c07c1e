#include "scanstop_common/stl_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace {

constexpr size_t kHeaderBytes = 84;
constexpr size_t kTriangleBytes = 50;

void addTriangle(TriangleMesh& mesh, const Eigen::Vector3f v[3], size_t index, const std::string& name) {
  for (int k = 0; k < 3; ++k) {
    if (!v[k].allFinite())
      throw IoError(name, "triangle " + std::to_string(index) + " has a non-finite (NaN or infinite) coordinate");
    if (v[k].cwiseAbs().maxCoeff() > kMaxFileCoordinateM) {
      std::ostringstream where;
      where << "triangle " << index << " vertex " << k + 1 << " (" << v[k].x() << ", " << v[k].y() << ", " << v[k].z()
            << ") lies beyond the 100000 m coordinate limit";
      throw IoError(name, where.str());
    }
  }
  const int base = static_cast<int>(mesh.vertices.size());
  for (int k = 0; k < 3; ++k) mesh.vertices.push_back(v[k]);
  mesh.faces.emplace_back(base, base + 1, base + 2);
}

TriangleMesh parseBinary(const std::string& data, const std::string& name) {
  uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, 4);
  const size_t expected = kHeaderBytes + kTriangleBytes * static_cast<size_t>(count);
  if (data.size() < expected)
    throw IoError(name, "truncated binary STL: the header announces " + std::to_string(count) + " triangles (" +
                            std::to_string(expected) + " bytes) but the file has only " + std::to_string(data.size()) +
                            " bytes");
  if (data.size() > expected)
    throw IoError(name, "not a valid binary STL: the header announces " + std::to_string(count) + " triangles (" +
                            std::to_string(expected) + " bytes) but the file has " + std::to_string(data.size()) +
                            " bytes");
  if (count == 0) throw IoError(name, "empty STL: no triangles");
  TriangleMesh mesh;
  mesh.vertices.reserve(3 * static_cast<size_t>(count));
  mesh.faces.reserve(count);
  for (uint32_t i = 0; i < count; ++i) {
    const char* rec = data.data() + kHeaderBytes + kTriangleBytes * i + 12;
    Eigen::Vector3f v[3];
    for (int k = 0; k < 3; ++k) std::memcpy(v[k].data(), rec + 12 * k, 12);
    addTriangle(mesh, v, i, name);
  }
  return mesh;
}

TriangleMesh parseAscii(const std::string& data, const std::string& name) {
  std::istringstream in(data);
  std::string word;
  TriangleMesh mesh;
  Eigen::Vector3f v[3];
  int corner = 0;
  size_t line = 1;
  auto fail = [&](const std::string& what) {
    throw IoError(name, "malformed ASCII STL near line " + std::to_string(line) + ": " + what);
  };
  std::string text_line;
  bool in_solid = false;
  while (std::getline(in, text_line)) {
    std::istringstream words(text_line);
    if (!(words >> word)) {
      ++line;
      continue;
    }
    if (word == "solid") {
      in_solid = true;
    } else if (word == "vertex") {
      if (!in_solid) fail("'vertex' outside 'solid'");
      if (corner >= 3) fail("more than three vertices in a facet");
      std::string xs, ys, zs;
      if (!(words >> xs >> ys >> zs)) fail("a vertex needs three coordinates");
      try {
        v[corner] = Eigen::Vector3f(std::stof(xs), std::stof(ys), std::stof(zs));
      } catch (const std::exception&) {
        fail("vertex coordinate is not a number");
      }
      ++corner;
    } else if (word == "endloop") {
      if (corner != 3) fail("a facet must have exactly three vertices, found " + std::to_string(corner));
      addTriangle(mesh, v, mesh.faces.size(), name);
      corner = 0;
    } else if (word == "facet" || word == "outer" || word == "endfacet" || word == "endsolid") {
      // structure words; the normal is recomputed from the winding
    } else {
      fail("unexpected word '" + word + "'");
    }
    ++line;
  }
  if (corner != 0) fail("file ends inside a facet");
  if (mesh.faces.empty()) throw IoError(name, "empty STL: no triangles");
  return mesh;
}

void putFloat(std::string& out, float f) { out.append(reinterpret_cast<const char*>(&f), 4); }

}  // namespace

TriangleMesh parseStl(const std::string& data, const std::string& name) {
  if (data.empty()) throw IoError(name, "empty file");
  const bool starts_solid = data.compare(0, 5, "solid") == 0;
  const size_t first_facet = data.find("facet");
  const bool has_facet = first_facet != std::string::npos && first_facet < 4096;
  if (starts_solid && has_facet) {
    // Binary files may also begin with "solid"; trust the size when it matches exactly.
    if (data.size() >= kHeaderBytes) {
      uint32_t count = 0;
      std::memcpy(&count, data.data() + 80, 4);
      if (count > 0 && data.size() == kHeaderBytes + kTriangleBytes * static_cast<size_t>(count))
        return parseBinary(data, name);
    }
    return parseAscii(data, name);
  }
  if (!starts_solid) {
    // Text that is not ASCII STL (an STL's binary header is free-form, but its counts are not text).
    const size_t probe = std::min<size_t>(data.size(), 512);
    bool printable = true;
    for (size_t i = 0; i < probe && printable; ++i) {
      const unsigned char c = static_cast<unsigned char>(data[i]);
      printable = (c >= 0x20 && c < 0x7f) || c == '\n' || c == '\r' || c == '\t';
    }
    if (printable && data.size() >= kHeaderBytes) {
      uint32_t count = 0;
      std::memcpy(&count, data.data() + 80, 4);
      if (data.size() != kHeaderBytes + kTriangleBytes * static_cast<size_t>(count))
        throw IoError(name, "not an STL file: it is text but does not start with 'solid'");
    }
  }
  if (data.size() < kHeaderBytes) {
    if (starts_solid) return parseAscii(data, name);
    throw IoError(name, "not an STL file: " + std::to_string(data.size()) +
                            " bytes is too short for a binary STL and it does not start with 'solid'");
  }
  return parseBinary(data, name);
}

TriangleMesh readStl(const std::string& path) { return parseStl(readFile(path), path); }

void writeStlBinary(const std::string& path, const TriangleMesh& mesh) {
  std::string out(80, '\0');
  const std::string title = "scanstop binary STL";
  out.replace(0, title.size(), title);
  const uint32_t count = static_cast<uint32_t>(mesh.faces.size());
  out.append(reinterpret_cast<const char*>(&count), 4);
  out.reserve(kHeaderBytes + kTriangleBytes * count);
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    const Eigen::Vector3f n = mesh.faceNormal(i);
    for (int k = 0; k < 3; ++k) putFloat(out, n[k]);
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) putFloat(out, mesh.vertices[mesh.faces[i][c]][k]);
    out.append(2, '\0');
  }
  writeFileAtomic(path, out);
}

void writeStlAscii(const std::string& path, const TriangleMesh& mesh) {
  std::ostringstream out;
  out << std::setprecision(9) << "solid scanstop\n";
  for (size_t i = 0; i < mesh.faces.size(); ++i) {
    const Eigen::Vector3f n = mesh.faceNormal(i);
    out << " facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n  outer loop\n";
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3f& v = mesh.vertices[mesh.faces[i][c]];
      out << "   vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
    }
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid scanstop\n";
  writeFileAtomic(path, out.str());
}

}  // namespace scanstop
