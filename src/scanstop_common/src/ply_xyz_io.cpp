#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/stl_io.h"

namespace scanstop {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parsePlyType(const std::string& name, PlyType& type) {
  static const std::pair<const char*, PlyType> kTypes[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& t : kTypes) {
    if (name == t.first) {
      type = t.second;
      return true;
    }
  }
  return false;
}

size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 0;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Float32;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

/// Sequential reader over the body of a PLY file in one of its three encodings.
class PlyBody {
 public:
  PlyBody(const std::string& data, size_t offset, int format, const std::string& name)
      : data_(data), pos_(offset), format_(format), name_(name) {}

  double read(PlyType t) {
    if (format_ == 0) return readAscii();
    const size_t n = plySize(t);
    if (pos_ + n > data_.size()) throw IoError(name_, "truncated PLY: data ends before all elements were read");
    unsigned char buf[8];
    std::memcpy(buf, data_.data() + pos_, n);
    pos_ += n;
    if (format_ == 2) std::reverse(buf, buf + n);
    switch (t) {
      case PlyType::Int8:
        return static_cast<int8_t>(buf[0]);
      case PlyType::UInt8:
        return buf[0];
      case PlyType::Int16: {
        int16_t v;
        std::memcpy(&v, buf, 2);
        return v;
      }
      case PlyType::UInt16: {
        uint16_t v;
        std::memcpy(&v, buf, 2);
        return v;
      }
      case PlyType::Int32: {
        int32_t v;
        std::memcpy(&v, buf, 4);
        return v;
      }
      case PlyType::UInt32: {
        uint32_t v;
        std::memcpy(&v, buf, 4);
        return v;
      }
      case PlyType::Float32: {
        float v;
        std::memcpy(&v, buf, 4);
        return v;
      }
      case PlyType::Float64: {
        double v;
        std::memcpy(&v, buf, 8);
        return v;
      }
    }
    return 0.0;
  }

 private:
  double readAscii() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    if (pos_ >= data_.size()) throw IoError(name_, "truncated PLY: data ends before all elements were read");
    const char* start = data_.c_str() + pos_;
    char* end = nullptr;
    const double v = std::strtod(start, &end);
    if (end == start) {
      const size_t line = 1 + static_cast<size_t>(std::count(data_.begin(), data_.begin() + pos_, '\n'));
      throw IoError(name_, "malformed PLY: '" + std::string(start, std::min<size_t>(12, data_.size() - pos_)) +
                               "' is not a number (line " + std::to_string(line) + ")");
    }
    pos_ += static_cast<size_t>(end - start);
    return v;
  }

  const std::string& data_;
  size_t pos_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  const std::string& name_;
};

}  // namespace

TriangleMesh parsePly(const std::string& data, const std::string& name) {
  if (data.empty()) throw IoError(name, "empty file");
  if (data.compare(0, 3, "ply") != 0) throw IoError(name, "not a PLY file: it does not start with 'ply'");
  const size_t header_end = data.find("end_header");
  if (header_end == std::string::npos) throw IoError(name, "malformed PLY: no 'end_header'");
  size_t body = data.find('\n', header_end);
  if (body == std::string::npos) throw IoError(name, "malformed PLY: nothing after 'end_header'");
  ++body;

  std::istringstream header(data.substr(0, header_end));
  std::string line;
  int format = -1;
  std::vector<PlyElement> elements;
  while (std::getline(header, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string word;
    if (!(words >> word)) continue;
    if (word == "format") {
      std::string f;
      words >> f;
      if (f == "ascii")
        format = 0;
      else if (f == "binary_little_endian")
        format = 1;
      else if (f == "binary_big_endian")
        format = 2;
      else
        throw IoError(name, "malformed PLY: unknown format '" + f + "'");
    } else if (word == "element") {
      PlyElement e;
      long long count = -1;
      if (!(words >> e.name >> count) || count < 0) throw IoError(name, "malformed PLY header line: " + line);
      for (const PlyElement& other : elements)
        if (other.name == e.name && (e.name == "vertex" || e.name == "face"))
          throw IoError(name, "malformed PLY: a second '" + e.name + "' element");
      e.count = static_cast<size_t>(count);
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) throw IoError(name, "malformed PLY: property before any element");
      PlyProperty p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type >> p.name;
        if (!parsePlyType(count_type, p.count_type) || !parsePlyType(item_type, p.type))
          throw IoError(name, "malformed PLY: unknown list type in '" + line + "'");
        p.is_list = true;
      } else {
        words >> p.name;
        if (!parsePlyType(type, p.type)) throw IoError(name, "malformed PLY: unknown property type '" + type + "'");
      }
      elements.back().properties.push_back(p);
    }
  }
  if (format < 0) throw IoError(name, "malformed PLY: no 'format' line");

  TriangleMesh mesh;
  PlyBody reader(data, body, format, name);
  for (const PlyElement& e : elements) {
    const bool is_vertex = e.name == "vertex";
    const bool is_face = e.name == "face";
    int ix = -1, iy = -1, iz = -1, inx = -1, iny = -1, inz = -1, ifaces = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const std::string& n = e.properties[k].name;
      if (n == "x") ix = static_cast<int>(k);
      if (n == "y") iy = static_cast<int>(k);
      if (n == "z") iz = static_cast<int>(k);
      if (n == "nx") inx = static_cast<int>(k);
      if (n == "ny") iny = static_cast<int>(k);
      if (n == "nz") inz = static_cast<int>(k);
      if (n == "vertex_indices" || n == "vertex_index") ifaces = static_cast<int>(k);
    }
    if (is_vertex && (ix < 0 || iy < 0 || iz < 0)) throw IoError(name, "PLY vertex element lacks x, y or z");
    const bool normals = is_vertex && inx >= 0 && iny >= 0 && inz >= 0;
    // Bound the element by the data (ply_fuzzer: a huge count without properties spun for minutes,
    // a huge vertex count reserved gigabytes): each item takes at least this many bytes.
    size_t min_item = 0;
    for (const PlyProperty& p : e.properties) min_item += format == 0 ? 2 : plySize(p.is_list ? p.count_type : p.type);
    if (min_item == 0) continue;
    if (e.count > (data.size() - body) / min_item + 1)
      throw IoError(name, "truncated PLY: element '" + e.name + "' announces " + std::to_string(e.count) +
                              " items, the data holds at most " + std::to_string((data.size() - body) / min_item + 1));
    if (is_vertex) {
      mesh.vertices.reserve(e.count);
      if (normals) mesh.normals.reserve(e.count);
    }
    std::vector<double> values(e.properties.size());
    std::vector<int> list;
    for (size_t i = 0; i < e.count; ++i) {
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.is_list) {
          values[k] = reader.read(p.type);
          continue;
        }
        const double n = reader.read(p.count_type);
        if (!(n >= 0 && n <= 1e6) || n != std::floor(n))
          throw IoError(name, "malformed PLY: list of " + std::to_string(n) + " items");
        list.resize(static_cast<size_t>(n));
        for (auto& item : list) {
          // Out-of-range or NaN values would make the cast undefined (ply_fuzzer, UBSan): -1 is an invalid index.
          const double v = reader.read(p.type);
          item = v >= -2147483648.0 && v <= 2147483647.0 ? static_cast<int>(v) : -1;
        }
        if (is_face && static_cast<int>(k) == ifaces) {
          // Fan-triangulate polygons.
          for (size_t t = 1; t + 1 < list.size(); ++t) mesh.faces.emplace_back(list[0], list[t], list[t + 1]);
        }
      }
      if (is_vertex) {
        mesh.vertices.emplace_back(values[ix], values[iy], values[iz]);
        if (normals) mesh.normals.emplace_back(values[inx], values[iny], values[inz]);
      }
    }
  }
  const int nv = static_cast<int>(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.faces[f][k] < 0 || mesh.faces[f][k] >= nv)
        throw IoError(name, "PLY face " + std::to_string(f) + " refers to vertex " + std::to_string(mesh.faces[f][k]) +
                                " of " + std::to_string(nv));
    }
  }
  return mesh;
}

namespace {
void putFloat(std::string& out, float f) { out.append(reinterpret_cast<const char*>(&f), 4); }
}  // namespace

TriangleMesh readPly(const std::string& path) { return parsePly(readFile(path), path); }

PointCloud readPlyCloud(const std::string& path) {
  TriangleMesh mesh = readPly(path);
  PointCloud cloud;
  cloud.points = std::move(mesh.vertices);
  cloud.normals = std::move(mesh.normals);
  cloud.setUnorganized();
  return cloud;
}

void writePly(const std::string& path, const TriangleMesh& mesh, bool binary) {
  const bool normals = mesh.normals.size() == mesh.vertices.size() && !mesh.normals.empty();
  std::ostringstream header;
  header << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\ncomment scanstop\n"
         << "element vertex " << mesh.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) header << "property float nx\nproperty float ny\nproperty float nz\n";
  if (!mesh.faces.empty())
    header << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\n";
  header << "end_header\n";
  std::string out = header.str();
  if (binary) {
    out.reserve(out.size() + mesh.vertices.size() * 24 + mesh.faces.size() * 13);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      for (int k = 0; k < 3; ++k) putFloat(out, mesh.vertices[i][k]);
      if (normals)
        for (int k = 0; k < 3; ++k) putFloat(out, mesh.normals[i][k]);
    }
    for (const auto& f : mesh.faces) {
      out.push_back(3);
      out.append(reinterpret_cast<const char*>(f.data()), 12);
    }
  } else {
    std::ostringstream body;
    body << std::setprecision(9);
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      body << mesh.vertices[i].x() << ' ' << mesh.vertices[i].y() << ' ' << mesh.vertices[i].z();
      if (normals) body << ' ' << mesh.normals[i].x() << ' ' << mesh.normals[i].y() << ' ' << mesh.normals[i].z();
      body << '\n';
    }
    for (const auto& f : mesh.faces) body << "3 " << f[0] << ' ' << f[1] << ' ' << f[2] << '\n';
    out += body.str();
  }
  writeFileAtomic(path, out);
}

void writePlyCloud(const std::string& path, const PointCloud& cloud, bool binary) {
  TriangleMesh mesh;
  mesh.vertices = cloud.points;
  mesh.normals = cloud.normals;
  writePly(path, mesh, binary);
}

PointCloud readXyz(const std::string& path) { return parseXyz(readFile(path), path); }

PointCloud parseXyz(const std::string& data, const std::string& path) {
  std::istringstream in(data);
  std::string line;
  PointCloud cloud;
  size_t line_no = 0;
  int columns = -1;
  while (std::getline(in, line)) {
    ++line_no;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<float> v;
    std::string w;
    while (words >> w) {
      char* end = nullptr;
      const float f = std::strtof(w.c_str(), &end);
      if (end == w.c_str() || *end != '\0')
        throw IoError(path, "line " + std::to_string(line_no) + ": '" + w + "' is not a number");
      v.push_back(f);
    }
    if (v.empty()) continue;
    if (v.size() != 3 && v.size() != 6)
      throw IoError(path, "line " + std::to_string(line_no) +
                              ": expected 3 (x y z) or 6 (x y z nx ny nz) values, found " + std::to_string(v.size()));
    if (columns < 0) columns = static_cast<int>(v.size());
    if (static_cast<int>(v.size()) != columns)
      throw IoError(path, "line " + std::to_string(line_no) + ": " + std::to_string(v.size()) +
                              " values where earlier lines have " + std::to_string(columns));
    cloud.points.emplace_back(v[0], v[1], v[2]);
    if (columns == 6) cloud.normals.emplace_back(v[3], v[4], v[5]);
  }
  if (cloud.points.empty()) throw IoError(path, "no points in XYZ file");
  cloud.setUnorganized();
  return cloud;
}

void writeXyz(const std::string& path, const PointCloud& cloud) {
  std::ostringstream out;
  out << std::setprecision(9);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud.points[i];
    out << p.x() << ' ' << p.y() << ' ' << p.z();
    if (cloud.hasNormals())
      out << ' ' << cloud.normals[i].x() << ' ' << cloud.normals[i].y() << ' ' << cloud.normals[i].z();
    out << '\n';
  }
  writeFileAtomic(path, out.str());
}

std::string coordinateProblem(const std::vector<Eigen::Vector3f>& points, const char* what) {
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (p.hasNaN() || p.cwiseAbs().maxCoeff() <= kMaxFileCoordinateM) continue;
    std::ostringstream o;
    o << what << ' ' << i << " (" << p.x() << ", " << p.y() << ", " << p.z()
      << ") lies beyond the 100000 m coordinate limit";
    return o.str();
  }
  return {};
}

PointCloud readCloud(const std::string& path) {
  const std::string problem = inputFileProblem(path);  // before the extension: a missing "x" is not "format '.'"
  if (!problem.empty()) throw IoError(path, problem);
  const std::string ext = fileExtension(path);
  const auto checked = [&path](PointCloud cloud) {
    const std::string far = coordinateProblem(cloud.points);
    if (!far.empty()) throw IoError(path, far);
    return cloud;
  };
  if (ext == "pcd") return checked(readPcd(path));
  if (ext == "ply") return checked(readPlyCloud(path));
  if (ext == "xyz" || ext == "txt") return checked(readXyz(path));
  throw IoError(path, ext.empty()
                          ? std::string("no file extension: unknown point-cloud format (expected .pcd, .ply or .xyz)")
                          : "unknown point-cloud format '." + ext + "' (expected .pcd, .ply or .xyz)");
}

void writeCloud(const std::string& path, const PointCloud& cloud) {
  const std::string problem = cloud.layoutProblem();
  if (!problem.empty()) throw IoError(path, "inconsistent cloud: " + problem);
  const std::string ext = fileExtension(path);
  if (ext == "pcd") return writePcd(path, cloud);
  if (ext == "ply") return writePlyCloud(path, cloud, true);
  if (ext == "xyz" || ext == "txt") return writeXyz(path, cloud);
  throw IoError(path, ext.empty()
                          ? std::string("no file extension: unknown point-cloud format (expected .pcd, .ply or .xyz)")
                          : "unknown point-cloud format '." + ext + "' (expected .pcd, .ply or .xyz)");
}

TriangleMesh readMesh(const std::string& path) {
  const std::string problem = inputFileProblem(path);
  if (!problem.empty()) throw IoError(path, problem);
  const std::string ext = fileExtension(path);
  if (ext == "stl") return readStl(path);
  if (ext == "ply") {
    TriangleMesh mesh = readPly(path);
    const std::string far = coordinateProblem(mesh.vertices, "vertex");
    if (!far.empty()) throw IoError(path, far);
    return mesh;
  }
  throw IoError(path, "unknown mesh format '." + ext + "' (expected .stl or .ply)");
}

void writeMesh(const std::string& path, const TriangleMesh& mesh) {
  const std::string ext = fileExtension(path);
  if (ext == "stl") return writeStlBinary(path, mesh);
  if (ext == "ply") return writePly(path, mesh, true);
  throw IoError(path, "unknown mesh format '." + ext + "' (expected .stl or .ply)");
}

}  // namespace scanstop
