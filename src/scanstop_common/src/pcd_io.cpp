// PCD files through PCL; the only translation unit of scanstop_common that includes PCL.
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace {

/// What the header says, checked for consistency with itself and with the file size.
struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<int> sizes;
  std::vector<char> types;
  std::vector<uint64_t> counts;
  uint64_t width = 0, height = 0, points = 0;
  std::string data;          ///< ascii, binary or binary_compressed
  uint64_t data_offset = 0;  ///< first byte after the DATA line
  uint64_t point_step = 0;   ///< bytes per point
};

bool parseUnsigned(const std::string& word, uint64_t max, uint64_t& out) {
  if (word.empty() || word.size() > 20) return false;
  for (char c : word)
    if (c < '0' || c > '9') return false;
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(word.c_str(), &end, 10);
  if (errno != 0 || *end != '\0' || v > max) return false;
  out = v;
  return true;
}

/// Parses and checks the header of the PCD file at path (size bytes long). Every problem is an IoError
/// naming the file: PCL's own reader trusts the header (a binary_compressed file without SIZE lines
/// made it overflow a heap buffer, see cloud_io_test PcdFuzzFindings).
PcdHeader readPcdHeader(std::istream& in, uint64_t size, const std::string& path) {
  const auto fail = [&path](const std::string& what) { throw IoError(path, "not a valid PCD file: " + what); };
  // The header entries in the order the PCD format prescribes; COUNT, VIEWPOINT and POINTS are optional.
  static const char* const kOrder[] = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                       "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  constexpr uint64_t kMaxFields = 4096, kMaxCount = 1u << 20, kMaxDim = 0xFFFFFFFFu;
  PcdHeader h;
  int last = -1;
  bool seen[10] = {};
  std::string line;
  size_t line_no = 0;
  uint64_t offset = 0;
  while (h.data.empty()) {
    if (!std::getline(in, line)) fail(line_no == 0 ? "no header" : "the header ends without a DATA line");
    ++line_no;
    offset += line.size() + 1;
    if (offset > (1u << 20)) fail("header longer than 1 MiB");
    const bool empty = line.empty();
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    if (!(words >> key)) {
      // PCL 1.13 skips an empty line but ends its header at a blank one ("\r\n" included) and then
      // crashed on the rest (pcd_fuzzer: SEGV in PCDReader::read): refuse what PCL would misread.
      if (empty) continue;
      fail("line " + std::to_string(line_no) + " is blank but not empty (PCL would end the header there)");
    }
    if (key[0] == '#') continue;
    if (key == "COLUMNS") key = "FIELDS";
    int k = 0;
    while (k < 10 && key != kOrder[k]) ++k;
    const std::string where = "line " + std::to_string(line_no) + " (" + key.substr(0, 20) + "): ";
    if (k == 10) fail(where + "unknown header entry");
    if (k <= last)
      fail(where +
           "repeated or out of order (the order is VERSION FIELDS SIZE TYPE COUNT WIDTH HEIGHT VIEWPOINT POINTS DATA)");
    if (k > 1 && last < 1) fail(where + "comes before FIELDS");
    last = k;
    seen[k] = true;
    std::vector<std::string> v;
    for (std::string w; words >> w;) v.push_back(w);
    const auto perField = [&](const char* what) {
      if (v.size() != h.fields.size())
        fail(where + std::to_string(v.size()) + " " + what + " for " + std::to_string(h.fields.size()) + " fields");
    };
    if (key == "VERSION") {
      continue;
    } else if (key == "FIELDS") {
      if (v.empty() || v.size() > kMaxFields) fail(where + "needs 1 to " + std::to_string(kMaxFields) + " field names");
      h.fields = v;
    } else if (key == "SIZE") {
      perField("sizes");
      for (const auto& w : v) {
        if (w != "1" && w != "2" && w != "4" && w != "8")
          fail(where + "size '" + w.substr(0, 20) + "' is not 1, 2, 4 or 8");
        h.sizes.push_back(w[0] - '0');
      }
    } else if (key == "TYPE") {
      if (!seen[2]) fail(where + "comes before SIZE");
      perField("types");
      for (size_t i = 0; i < v.size(); ++i) {
        if (v[i] != "I" && v[i] != "U" && v[i] != "F")
          fail(where + "type '" + v[i].substr(0, 20) + "' is not I, U or F");
        if (v[i] == "F" && h.sizes[i] != 4 && h.sizes[i] != 8)
          fail(where + "field '" + h.fields[i] + "' is a float of " + std::to_string(h.sizes[i]) + " bytes");
        h.types.push_back(v[i][0]);
      }
    } else if (key == "COUNT") {
      perField("counts");
      for (const auto& w : v) {
        uint64_t c = 0;
        if (!parseUnsigned(w, kMaxCount, c) || c == 0)
          fail(where + "count '" + w.substr(0, 20) + "' is not 1 to " + std::to_string(kMaxCount));
        h.counts.push_back(c);
      }
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      uint64_t n = 0;
      if (v.size() != 1 || !parseUnsigned(v[0], kMaxDim, n))
        fail(where + "needs one integer from 0 to " + std::to_string(kMaxDim));
      (key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : h.points) = n;
    } else if (key == "VIEWPOINT") {
      if (v.size() != 7) fail(where + "needs 7 numbers (tx ty tz qw qx qy qz)");
      for (const auto& w : v) {
        char* end = nullptr;
        std::strtod(w.c_str(), &end);
        if (end == w.c_str() || *end != '\0') fail(where + "'" + w.substr(0, 20) + "' is not a number");
      }
    } else if (key == "DATA") {
      if (v.size() != 1 || (v[0] != "ascii" && v[0] != "binary" && v[0] != "binary_compressed"))
        fail(where + "needs ascii, binary or binary_compressed");
      h.data = v[0];
    }
  }
  if (!seen[2] || !seen[3]) fail("the header lacks SIZE or TYPE");
  if (!seen[5] || !seen[6]) fail("the header lacks WIDTH or HEIGHT");
  if (h.counts.empty()) h.counts.assign(h.fields.size(), 1);
  if (h.width * h.height > kMaxDim) fail("WIDTH x HEIGHT exceeds " + std::to_string(kMaxDim) + " points");
  if (!seen[8]) fail("the header lacks POINTS");
  if (h.points != h.width * h.height)
    fail("WIDTH x HEIGHT = " + std::to_string(h.width) + " x " + std::to_string(h.height) + " but POINTS " +
         std::to_string(h.points));
  for (size_t i = 0; i < h.fields.size(); ++i) h.point_step += h.sizes[i] * h.counts[i];
  h.data_offset = offset;
  // PCL 1.13 reads on after the DATA line: an empty line or a comment is skipped, a line whose first
  // word starts like a header entry is read as one (a second DATA moves the data, a WIDTH changes the
  // size) and anything else ends its header. Binary data that begins like that made PCL request a
  // ~100 TB allocation (pcd_fuzzer, cloud_io_test PcdFuzzFindings): refuse what PCL would misread.
  for (int skipped = 0; skipped < 1000; ++skipped) {
    std::string next;
    char c = 0;
    while (next.size() < 256 && in.get(c) && c != '\n') next.push_back(c);
    if (next.size() == 256) in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    const bool at_end = !in;
    if (next.empty()) {
      if (at_end) break;
      continue;
    }
    std::istringstream words(next);
    std::string first;
    if (!(words >> first)) break;
    if (first[0] == '#') {
      if (at_end) break;
      continue;
    }
    for (const char* entry : kOrder)
      if (first.compare(0, std::strlen(entry), entry) == 0 || first.compare(0, 7, "COLUMNS") == 0) {
        std::string shown = first.substr(0, 20);
        for (char& ch : shown)
          if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) > 0x7e) ch = '?';
        fail("the data begins with '" + shown + "', which PCL would read as a header line");
      }
    break;
  }
  in.clear();
  in.seekg(static_cast<std::streamoff>(offset));
  const uint64_t body = size > offset ? size - offset : 0;
  if (h.data == "binary") {
    const uint64_t need = h.points * h.point_step;  // < 2^32 * 2^35: no overflow
    if (body < need)
      throw IoError(path, "truncated PCD: " + std::to_string(h.points) + " points need " + std::to_string(need) +
                              " data bytes, the file has " + std::to_string(body));
  } else if (h.data == "binary_compressed") {
    if (h.points == 0) return h;
    if (body < 8) throw IoError(path, "truncated PCD: the compressed data lacks its size fields");
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    uint32_t sizes[2] = {0, 0};
    in.read(reinterpret_cast<char*>(sizes), 8);
    if (!in) throw IoError(path, "truncated PCD: the compressed data lacks its size fields");
    if (sizes[1] != h.points * h.point_step)
      fail("the compressed data unpacks to " + std::to_string(sizes[1]) + " bytes, " + std::to_string(h.points) +
           " points need " + std::to_string(h.points * h.point_step));
    if (sizes[0] > body - 8)
      throw IoError(path, "truncated PCD: " + std::to_string(sizes[0]) + " compressed bytes announced, the file has " +
                              std::to_string(body - 8));
    // LZF expands at most ~90-fold (a 3-byte back reference yields 264 bytes).
    if (sizes[1] > 100ull * sizes[0] + 64) fail("the compressed data cannot unpack to the announced size");
  } else {
    const uint64_t values = std::accumulate(h.counts.begin(), h.counts.end(), uint64_t{0});
    if (h.points * values > (body + 1) / 2)  // each value takes a character and a separator
      throw IoError(path, "truncated PCD: " + std::to_string(h.points) + " points announced, the file has only " +
                              std::to_string(body) + " data bytes");
    // ASCII data is checked line by line: PCL 1.13 made a ~100 TB allocation on garbage data lines
    // (pcd_fuzzer, cloud_io_test PcdFuzzFindings).
    in.clear();
    in.seekg(static_cast<std::streamoff>(offset));
    uint64_t points = 0;
    for (size_t data_line = line_no + 1; std::getline(in, line); ++data_line) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (line.find_first_not_of(" \t") == std::string::npos) continue;
      std::istringstream words(line);
      uint64_t n = 0;
      for (std::string w; words >> w; ++n) {
        char* end = nullptr;
        std::strtod(w.c_str(), &end);
        if (end == w.c_str() || *end != '\0')
          fail("line " + std::to_string(data_line) + ": '" + w.substr(0, 20) + "' is not a number");
      }
      if (n != values)
        fail("line " + std::to_string(data_line) + ": " + std::to_string(n) + " values, a point has " +
             std::to_string(values));
      if (++points > h.points) fail("more than the " + std::to_string(h.points) + " points the header announces");
    }
    if (points < h.points)
      throw IoError(path, "truncated PCD: " + std::to_string(points) + " of " + std::to_string(h.points) + " points");
  }
  return h;
}

PcdHeader checkPcdFile(const std::string& path) {
  const std::string problem = inputFileProblem(path);
  if (!problem.empty()) throw IoError(path, problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, errno == ENOENT ? "no such file" : std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size <= 0) throw IoError(path, "empty file");
  in.seekg(0);
  return readPcdHeader(in, static_cast<uint64_t>(size), path);
}

const pcl::PCLPointField* findField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  for (const auto& f : blob.fields)
    if (f.name == name) return &f;
  return nullptr;
}

/// One value of a field as a float, whatever its stored type.
float fieldValue(const uint8_t* p, uint8_t type) {
  switch (type) {
    case pcl::PCLPointField::INT8: {
      int8_t v;
      std::memcpy(&v, p, 1);
      return v;
    }
    case pcl::PCLPointField::UINT8:
      return *p;
    case pcl::PCLPointField::INT16: {
      int16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case pcl::PCLPointField::UINT16: {
      uint16_t v;
      std::memcpy(&v, p, 2);
      return v;
    }
    case pcl::PCLPointField::INT32: {
      int32_t v;
      std::memcpy(&v, p, 4);
      return static_cast<float>(v);
    }
    case pcl::PCLPointField::UINT32: {
      uint32_t v;
      std::memcpy(&v, p, 4);
      return static_cast<float>(v);
    }
    case pcl::PCLPointField::INT64: {
      int64_t v;
      std::memcpy(&v, p, 8);
      return static_cast<float>(v);
    }
    case pcl::PCLPointField::UINT64: {
      uint64_t v;
      std::memcpy(&v, p, 8);
      return static_cast<float>(v);
    }
    case pcl::PCLPointField::FLOAT32: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case pcl::PCLPointField::FLOAT64: {
      double v;
      std::memcpy(&v, p, 8);
      // Out-of-range doubles become infinities (a plain cast would be undefined).
      return std::fabs(v) > std::numeric_limits<float>::max() ? (v > 0 ? INFINITY : -INFINITY) : static_cast<float>(v);
    }
    default:
      return NAN;
  }
}

size_t fieldBytes(uint8_t type) {
  switch (type) {
    case pcl::PCLPointField::INT8:
    case pcl::PCLPointField::UINT8:
      return 1;
    case pcl::PCLPointField::INT16:
    case pcl::PCLPointField::UINT16:
      return 2;
    case pcl::PCLPointField::INT32:
    case pcl::PCLPointField::UINT32:
    case pcl::PCLPointField::FLOAT32:
      return 4;
    case pcl::PCLPointField::INT64:
    case pcl::PCLPointField::UINT64:
    case pcl::PCLPointField::FLOAT64:
      return 8;
    default:
      return 0;
  }
}

}  // namespace

std::string pcdFileProblem(const std::string& path) {
  try {
    checkPcdFile(path);
  } catch (const IoError& e) {
    return e.problem();
  }
  return {};
}

PointCloud readPcd(const std::string& path) {
  const PcdHeader header = checkPcdFile(path);
  PointCloud cloud;
  if (header.points == 0) {
    cloud.setUnorganized();
    return cloud;
  }
  pcl::PCLPointCloud2 blob;
  pcl::PCDReader reader;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0;
  int status = -1;
  try {
    status = reader.read(path, blob, origin, orientation, version);
  } catch (const std::exception& e) {
    throw IoError(path, std::string("not a valid PCD file: ") + e.what());
  }
  if (status < 0) throw IoError(path, "not a valid PCD file (PCL could not parse its header or data)");
  const size_t n = static_cast<size_t>(blob.width) * blob.height;
  if (blob.point_step == 0 || blob.data.size() < n * blob.point_step)
    throw IoError(path, "not a valid PCD file: PCL returned " + std::to_string(blob.data.size()) + " data bytes for " +
                            std::to_string(n) + " points of " + std::to_string(blob.point_step) + " bytes");
  const auto field = [&](const std::string& name) -> const pcl::PCLPointField* {
    const pcl::PCLPointField* f = findField(blob, name);
    if (f && (fieldBytes(f->datatype) == 0 || f->offset + fieldBytes(f->datatype) > blob.point_step))
      throw IoError(path, "not a valid PCD file: field '" + name + "' does not fit in a point");
    return f;
  };
  const pcl::PCLPointField* fx = field("x");
  const pcl::PCLPointField* fy = field("y");
  const pcl::PCLPointField* fz = field("z");
  if (!fx || !fy || !fz) throw IoError(path, "PCD file lacks x, y or z fields");
  const pcl::PCLPointField* fnx = field("normal_x");
  const pcl::PCLPointField* fny = field("normal_y");
  const pcl::PCLPointField* fnz = field("normal_z");
  const bool normals = fnx && fny && fnz;
  const pcl::PCLPointField* frange = normals ? nullptr : field("range");
  cloud.points.resize(n);
  if (normals) cloud.normals.resize(n);
  if (frange) cloud.ranges.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = blob.data.data() + i * blob.point_step;
    cloud.points[i] =
        Eigen::Vector3f(fieldValue(p + fx->offset, fx->datatype), fieldValue(p + fy->offset, fy->datatype),
                        fieldValue(p + fz->offset, fz->datatype));
    if (normals)
      cloud.normals[i] =
          Eigen::Vector3f(fieldValue(p + fnx->offset, fnx->datatype), fieldValue(p + fny->offset, fny->datatype),
                          fieldValue(p + fnz->offset, fnz->datatype));
    if (frange) cloud.ranges[i] = fieldValue(p + frange->offset, frange->datatype);
  }
  cloud.width = blob.width;
  cloud.height = blob.height;
  return cloud;
}

void writePcd(const std::string& path, const PointCloud& cloud) {
  const std::string problem = outputFileProblem(path);  // PCL would only say "Error during open!"
  if (!problem.empty()) throw IoError(path, "cannot write: " + problem);
  const std::string tmp = temporaryPathFor(path);
  int result = 0;
  const auto fill = [&cloud](auto& pc) {
    pc.width = cloud.width;
    pc.height = cloud.height;
    pc.is_dense = cloud.countFinite() == cloud.size();
    pc.points.resize(cloud.size());
  };
  if (cloud.hasNormals()) {
    pcl::PointCloud<pcl::PointNormal> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x();
      q.y = cloud.points[i].y();
      q.z = cloud.points[i].z();
      q.normal_x = cloud.normals[i].x();
      q.normal_y = cloud.normals[i].y();
      q.normal_z = cloud.normals[i].z();
      q.curvature = 0.0f;
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  } else if (cloud.hasRanges()) {
    pcl::PointCloud<pcl::PointWithRange> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x();
      q.y = cloud.points[i].y();
      q.z = cloud.points[i].z();
      q.range = cloud.ranges[i];
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  } else {
    pcl::PointCloud<pcl::PointXYZ> pc;
    fill(pc);
    for (size_t i = 0; i < cloud.size(); ++i) {
      auto& q = pc.points[i];
      q.x = cloud.points[i].x();
      q.y = cloud.points[i].y();
      q.z = cloud.points[i].z();
    }
    result = pcl::io::savePCDFileBinary(tmp, pc);
  }
  if (result < 0) {
    std::remove(tmp.c_str());
    throw IoError(path, "could not write PCD file");
  }
  // PCL's writer does not fsync: commitTemporaryFile flushes before the rename makes the file visible.
  commitTemporaryFile(tmp, path);
}

}  // namespace scanstop
