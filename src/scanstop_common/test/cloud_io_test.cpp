#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <limits>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/shared_data.h"
#include "scanstop_common/stl_io.h"
#include "test_util.h"

namespace scanstop {
namespace {

using test::expectIoError;
using test::TempDir;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// A 3 x 4 organized scan with two invalid (NaN) points and ranges.
PointCloud organizedScan() {
  PointCloud c;
  c.width = 4;
  c.height = 3;
  for (uint32_t r = 0; r < c.height; ++r)
    for (uint32_t b = 0; b < c.width; ++b) {
      c.points.emplace_back(0.5f * b + 0.125f, -0.25f * r, 1.0f + 0.01f * (r * 4 + b));
      c.ranges.push_back(c.points.back().norm());
    }
  c.points[5] = Eigen::Vector3f::Constant(kNaN);
  c.ranges[5] = kNaN;
  c.points[11] = Eigen::Vector3f::Constant(kNaN);
  c.ranges[11] = kNaN;
  return c;
}

void expectSamePoints(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a.points[i].allFinite()) {
      EXPECT_FALSE(b.points[i].allFinite()) << "point " << i << " should stay NaN";
      continue;
    }
    EXPECT_TRUE(a.points[i].isApprox(b.points[i], 1e-6f)) << "point " << i;
  }
}

TEST(CloudIo, PcdRoundTripKeepsOrganizationNaNAndRanges) {
  TempDir dir;
  const PointCloud c = organizedScan();
  writeCloud(dir.file("scan.pcd"), c);
  const PointCloud back = readCloud(dir.file("scan.pcd"));
  EXPECT_EQ(back.width, 4u);
  EXPECT_EQ(back.height, 3u);
  expectSamePoints(c, back);
  ASSERT_TRUE(back.hasRanges());
  EXPECT_TRUE(std::isnan(back.ranges[5]));
  EXPECT_FLOAT_EQ(back.ranges[0], c.ranges[0]);
  EXPECT_EQ(back.countFinite(), 10u);
}

TEST(CloudIo, PcdRoundTripWithNormals) {
  TempDir dir;
  PointCloud c;
  c.push_back({1, 2, 3});
  c.push_back({kNaN, kNaN, kNaN});
  c.normals = {{0, 0, 1}, {1, 0, 0}};
  writeCloud(dir.file("n.pcd"), c);
  const PointCloud back = readCloud(dir.file("n.pcd"));
  expectSamePoints(c, back);
  ASSERT_TRUE(back.hasNormals());
  EXPECT_TRUE(back.normals[0].isApprox(Eigen::Vector3f(0, 0, 1)));
}

TEST(CloudIo, PlyRoundTripBinaryAndAsciiWithNaN) {
  TempDir dir;
  PointCloud c = organizedScan();
  c.ranges.clear();
  c.normals.assign(c.size(), Eigen::Vector3f(0, 0, 1));
  writePlyCloud(dir.file("b.ply"), c, true);
  writePlyCloud(dir.file("a.ply"), c, false);
  for (const char* name : {"b.ply", "a.ply"}) {
    const PointCloud back = readCloud(dir.file(name));
    expectSamePoints(c, back);
    ASSERT_EQ(back.normals.size(), c.size()) << name;
  }
}

TEST(CloudIo, PlyMeshRoundTripKeepsFaces) {
  TempDir dir;
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  writeMesh(dir.file("m.ply"), m);
  const TriangleMesh back = readMesh(dir.file("m.ply"));
  ASSERT_EQ(back.faces.size(), 4u);
  EXPECT_EQ(back.faces[3], Eigen::Vector3i(1, 2, 3));
  writeMesh(dir.file("m.stl"), m);
  EXPECT_EQ(readMesh(dir.file("m.stl")).faces.size(), 4u);
}

TEST(CloudIo, XyzRoundTripWithNaN) {
  TempDir dir;
  PointCloud c = organizedScan();
  c.ranges.clear();
  writeCloud(dir.file("c.xyz"), c);
  const PointCloud back = readCloud(dir.file("c.xyz"));
  expectSamePoints(c, back);
}

TEST(CloudIo, MalformedInputsNameFileAndProblem) {
  TempDir dir;
  const std::string xyz = dir.write("bad.xyz", "1 2 3\n4 5\n");
  expectIoError([&] { readCloud(xyz); }, xyz, "line 2: expected 3");
  const std::string xyz2 = dir.write("bad2.xyz", "1 2 3\n4 five 6\n");
  expectIoError([&] { readCloud(xyz2); }, xyz2, "'five' is not a number");
  const std::string ply = dir.write("bad.ply",
                                    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                    "property float y\nproperty float z\nend_header\n1 2 3\n4 5 6\n");
  expectIoError([&] { readCloud(ply); }, ply, "truncated PLY");
  const std::string notply = dir.write("x.ply", "hello");
  expectIoError([&] { readCloud(notply); }, notply, "not a PLY file");
  const std::string pcd = dir.write("bad.pcd", "this is not a pcd file\n");
  expectIoError([&] { readCloud(pcd); }, pcd, "not a valid PCD file");
  expectIoError([&] { readCloud("/nonexistent/a.pcd"); }, "/nonexistent/a.pcd", "no such file");
  expectIoError([&] { readCloud(dir.write("a.obj", "o\n")); }, dir.file("a.obj"), "unknown point-cloud format");
  PointCloud broken;
  broken.points.resize(3);
  broken.width = 2;
  expectIoError([&] { writeCloud(dir.file("w.pcd"), broken); }, dir.file("w.pcd"), "inconsistent cloud");
}

// Issue #22 class 3: a point at 1e30 m went into fuse_map's and plan_step's grids unnoticed.
TEST(CloudIo, CoordinatesBeyondTheLimitAreRefusedNamingThePoint) {
  TempDir dir;
  const std::string pcd =
      dir.write("far.pcd",
                "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1 0 0\n0 1 0\n1e30 0 0\n");
  expectIoError([&] { readCloud(pcd); }, pcd, "point 2 (1e+30, 0, 0) lies beyond the 100000 m coordinate limit");
  const std::string xyz = dir.write("inf.xyz", "1 2 3\nnan nan nan\n4 -inf 6\n");
  expectIoError([&] { readCloud(xyz); }, xyz, "point 2 (4, -inf, 6) lies beyond the 100000 m coordinate limit");
  const std::string mesh = dir.write("far.ply",
                                     "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                     "property float y\nproperty float z\nelement face 1\n"
                                     "property list uchar int vertex_indices\nend_header\n"
                                     "0 0 0\n1 0 0\n0 200000 0\n3 0 1 2\n");
  expectIoError([&] { readMesh(mesh); }, mesh, "vertex 2 (0, 200000, 0) lies beyond the 100000 m coordinate limit");
  // NaN points (missing returns of an organized scan) and points within the limit are kept.
  const std::string ok = dir.write("ok.xyz", "1 2 3\nnan nan nan\n99999 -99999 0\n");
  EXPECT_EQ(readCloud(ok).size(), 3u);
}

TEST(FileUtil, MakeDirectoriesCreatesParentsAcceptsExistingAndNamesAFileInTheWay) {
  TempDir dir;
  const std::string nested = dir.file("a/b/c");
  makeDirectories(nested);
  struct stat st;
  ASSERT_EQ(::stat(nested.c_str(), &st), 0);
  EXPECT_TRUE(S_ISDIR(st.st_mode));
  makeDirectories(nested);  // exists already (another process may have made it a moment ago): fine
  const std::string file = dir.write("f", "x");
  expectIoError([&] { makeDirectories(file + "/sub"); }, file + "/sub", "cannot create directory: Not a directory");
  expectIoError([&] { makeDirectories(file); }, file, "exists but is not a directory");
}

TEST(CloudIo, AtomicWriteLeavesNoTemporaryFiles) {
  TempDir dir;
  writeFileAtomic(dir.file("f.txt"), "one");
  writeFileAtomic(dir.file("f.txt"), "two");
  EXPECT_EQ(readFile(dir.file("f.txt")), "two");
  EXPECT_THROW(writeFileAtomic("/nonexistent/dir/f.txt", "x"), IoError);
}

const char* const kAsciiHead = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int c : b) s.push_back(static_cast<char>(c));
  return s;
}
std::string f32(float v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string f64(double v) { return std::string(reinterpret_cast<const char*>(&v), 8); }
std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

// Inputs the libFuzzer target pcd_fuzzer found (test/fuzz/pcd_fuzz.cpp); each crashed before the fix.
TEST(CloudIo, PcdFuzzFindings) {
  TempDir dir;
  // 1. PCL 1.13's PCDReader::readBodyBinary overflowed a 12-byte heap buffer (ASan heap-buffer-overflow
  //    in memcpy) on a binary_compressed file whose header has no SIZE/TYPE lines and a garbled FIELDS
  //    line. Our header check now rejects it before PCL sees it.
  const std::string overflow =
      dir.write("overflow.pcd",
                std::string("VERSION 0.7\nFIELDS x y zIELDS x y ") + bytes({0x10, 0x00}) +
                    "TYPE1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA binary_compressed\n" +
                    bytes({0x0d, 0, 0, 0, 0x0c, 0, 0, 0, 0x0b, 0, 0, 0x80, 0x3f, 0, 0, 0, 0x40, 0, 0, 0x40, 0x40}));
  expectIoError([&] { readPcd(overflow); }, overflow, "the header lacks SIZE or TYPE");
  // 2. Our own header check (first version) read the SIZE list for a TYPE line when SIZE was missing
  //    (UBSan: reference binding to null pointer in std::vector::operator[]).
  const std::string type_first =
      dir.write("type_first.pcd",
                std::string("VERSION 0.7\nFIELDS 4 4\nTYPE F Fary_compressed\n") +
                    bytes({0x0d, 0,   0,   0,   0x0c, 0, 0,    'T',  'H', ' ', '2', '\n', 'H', 'P', 'E',  ' ',
                           'F',  ' ', 'F', 'a', 0,    0, 0x80, 0x3f, 0,   0,   0,   0x40, 0,   0,   0x40, 0x40}));
  expectIoError([&] { readPcd(type_first); }, type_first, "comes before SIZE");
  // 3. PCL 1.13's PCDReader::read requested a ~100 TB allocation (ASan allocation-size-too-big) for an
  //    ASCII PCD with a valid header and garbage data lines. Data lines are now checked first.
  const std::string garbage = dir.write(
      "garbage_ascii.pcd", std::string("# .PCD z0loul Data:f") + bytes({8, 0, 0, 0, 0, 0, 0, 0}) +
                               "IELDS x y z0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                               "VIEWPOINT 1 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n# .PVERSI" +
                               std::string(19, '\xff') + "t\x02VER" + bytes({0xad, 0xb6, 0xb3, 0xb8}) + " 0.7\nFIELDS" +
                               bytes({1, 0, 0}) + "\nIO RSI .7CD v0.Xv- Poi 2\nVIEWPOINT 0 0 0 1");
  // (Refused before its data lines are read: PCL would take the line after the comment for a FIELDS line.)
  expectIoError([&] { readPcd(garbage); }, garbage, "which PCL would read as a header line");
  // 4. PCL 1.13 reads header lines after DATA too: binary data starting "DATA" was taken for a second
  //    DATA line (the data moved) and PCDReader::read requested a ~100 TB allocation (ASan
  //    allocation-size-too-big, pcd_fuzzer in CI). Data that PCL would read as a header line is refused.
  const std::string second_data = dir.write(
      "second_data.pcd",
      std::string("# .PCD v0.7TY - Point Cloud Data file foVERt\nVERSION 0.7\nFIELDS .x y zr ange\nSIZE 4 4 4 4\n"
                  "TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA binary\n") +
          bytes({0x44, 0x41, 0x54, 0x41, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                 0x00, 0x00, 0x45, 0x52, 0x53, 0x49, 0x4f, 0x4e, 0x20, 0x43, 0x31, 0x0a, 0x43, 0x4f, 0x4c, 0x55,
                 0x4d, 0x4e, 0x53, 0x80, 0x3f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0x00,
                 0x00, 0x00, 0x00, 0x80, 0x3f, 0x00, 0x00, 0xc0, 0x7f, 0x00, 0x00, 0xc0, 0x7f, 0x00, 0x00, 0xc0,
                 0x7f, 0x00, 0x00, 0xc0, 0x7f, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x35, 0x00,
                 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40, 0x00, 0x00, 0x00, 0x40}));
  expectIoError([&] { readPcd(second_data); }, second_data, "the data begins with 'DATA");
  // Binary data that merely starts with a comment character or a newline is data (PCL skips such
  // lines and keeps the data where the DATA line put it).
  PointCloud hash_first;
  hash_first.points = {{1.0f, 0.0f, 0.0f}};
  hash_first.setUnorganized();
  std::memcpy(&hash_first.points[0].x(), "#\n\x00\x3f", 4);
  const std::string hash_file = dir.file("hash_first.pcd");
  writePcd(hash_file, hash_first);
  EXPECT_EQ(readPcd(hash_file).points.at(0).x(), hash_first.points[0].x());
  const std::string short_ascii = dir.write(
      "short.pcd", std::string(kAsciiHead) + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1.000 2.000 3.000\n\n");
  expectIoError([&] { readPcd(short_ascii); }, short_ascii, "truncated PCD: 1 of 2 points");
  const std::string wide =
      dir.write("wide.pcd", std::string(kAsciiHead) + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3 4\n");
  expectIoError([&] { readPcd(wide); }, wide, "line 9: 4 values, a point has 3");
}

// Found by ply_fuzzer: a second vertex element (the first with normals, the second without) gave a mesh
// with fewer normals than vertices.
TEST(CloudIo, PlyFuzzFindings) {
  TempDir dir;
  const std::string two =
      dir.write("two_vertex.ply",
                "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                "property float nx\nproperty float ny\nproperty float nz\nelement vertex 1\nproperty float x\n"
                "property float y\nproperty float z\nend_header\n0 0 0 0 0 1\n1 1 1\n");
  expectIoError([&] { readPly(two); }, two, "a second 'vertex' element");
  // A face index out of int range or a NaN list count was cast to an integer (UBSan: undefined behaviour).
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list float double vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n";
  const std::string huge = dir.write("huge_index.ply", head + "3 0 1 1e300\n");
  expectIoError([&] { readPly(huge); }, huge, "PLY face 0 refers to vertex -1 of 3");
  const std::string nan_count = dir.write("nan_count.ply", head + "nan 0 1 2\n");
  expectIoError([&] { readPly(nan_count); }, nan_count, "malformed PLY: list of nan items");
  // A huge element count: bounded by the data instead of looping or reserving gigabytes (timeout).
  const std::string many = dir.write("many.ply",
                                     "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
                                     "property float x\nproperty float y\nproperty float z\nend_header\n" +
                                         std::string(24, '\0'));
  expectIoError([&] { readPly(many); }, many, "truncated PLY: element 'vertex' announces 1000000000 items");
  const std::string empty_el = dir.write("empty_element.ply",
                                         "ply\nformat ascii 1.0\nelement junk 4000000000\n"
                                         "element vertex 1\nproperty float x\nproperty float y\n"
                                         "property float z\nend_header\n1 2 3\n");
  EXPECT_EQ(readPly(empty_el).vertices.size(), 1u);
}

// The header check in front of PCL: every inconsistency is an IoError naming the file and the problem.
TEST(CloudIo, PcdHeaderIsCheckedBeforePcl) {
  TempDir dir;
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const auto pcd = [&](const std::string& name, const std::string& text) { return dir.write(name, text); };
  const std::string p1 =
      pcd("huge_ascii.pcd", head + "WIDTH 1000000000\nHEIGHT 1\nPOINTS 1000000000\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(p1); }, p1, "truncated PCD: 1000000000 points announced");
  const std::string p2 = pcd("mismatch.pcd", head + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n1 2 3\n1 2 3\n1 2 3\n");
  expectIoError([&] { readPcd(p2); }, p2, "WIDTH x HEIGHT = 2 x 2 but POINTS 3");
  const std::string p3 =
      pcd("size3.pcd", "FIELDS x y z\nSIZE 4 3 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(p3); }, p3, "size '3' is not 1, 2, 4 or 8");
  const std::string p4 =
      pcd("order.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nHEIGHT 1\nWIDTH 1\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(p4); }, p4, "line 5 (WIDTH): repeated or out of order");
  const std::string p5 = pcd("types.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(p5); }, p5, "2 types for 3 fields");
  const std::string p6 = pcd("nodata.pcd", head + "WIDTH 1\nHEIGHT 1\n");
  expectIoError([&] { readPcd(p6); }, p6, "without a DATA line");
  const std::string p7 =
      pcd("float2.pcd", "FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(p7); }, p7, "field 'z' is a float of 2 bytes");
  // Compressed: the unpacked size must match the points, the packed bytes must be there.
  const std::string raw = f32(1) + f32(2) + f32(3);
  const std::string lzf = std::string(1, 11) + raw;  // one literal run of 12 bytes
  const std::string chead = head + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary_compressed\n";
  const std::string good = pcd("c.pcd", chead + le32(13) + le32(12) + lzf);
  const PointCloud c = readPcd(good);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.points[0], Eigen::Vector3f(1, 2, 3));
  const std::string c2 = pcd("c2.pcd", chead + le32(13) + le32(4000000) + lzf);
  expectIoError([&] { readPcd(c2); }, c2, "unpacks to 4000000 bytes, 1 points need 12");
  const std::string c3 = pcd("c3.pcd", chead + le32(100) + le32(12) + lzf);
  expectIoError([&] { readPcd(c3); }, c3, "truncated PCD: 100 compressed bytes announced");
  const std::string c4 = pcd("c4.pcd", chead + le32(13));
  expectIoError([&] { readPcd(c4); }, c4, "lacks its size fields");
  // Binary: a data section cut short.
  const std::string b = pcd("b.pcd", head + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n" + raw + f32(4));
  expectIoError([&] { readPcd(b); }, b, "truncated PCD: 2 points need 24 data bytes, the file has 16");
  EXPECT_EQ(pcdFileProblem(good), "");
  EXPECT_NE(pcdFileProblem(b).find("truncated PCD"), std::string::npos);
}

// Field types other than float32 are converted (PCL's fromPCLPointCloud2 silently left such points at 0).
TEST(CloudIo, PcdWithDoubleAndIntegerFields) {
  TempDir dir;
  const std::string p =
      dir.write("d.pcd", "FIELDS x y z range\nSIZE 8 8 8 2\nTYPE F F F U\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n" +
                             f64(1.5) + f64(-2.25) + f64(1e300) + bytes({7, 1}));
  const PointCloud c = readPcd(p);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c.points[0].x(), 1.5f);
  EXPECT_EQ(c.points[0].y(), -2.25f);
  EXPECT_TRUE(std::isinf(c.points[0].z()));  // out of float range: infinite, not undefined
  ASSERT_TRUE(c.hasRanges());
  EXPECT_EQ(c.ranges[0], 263.0f);
  const std::string empty =
      dir.write("e.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA binary\n");
  EXPECT_EQ(readPcd(empty).size(), 0u);
  const std::string nopoints =
      dir.write("n.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nDATA ascii\n1 2 3\n");
  expectIoError([&] { readPcd(nopoints); }, nopoints, "the header lacks POINTS");
}

// Every writer is atomic: a temporary file in the same directory, fsync, rename; none is left behind,
// and a failed write leaves the old file untouched.
TEST(CloudIo, EveryWriterIsAtomic) {
  TempDir dir;
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}};
  PointCloud cloud;
  cloud.push_back({1, 2, 3});
  writeCloud(dir.file("c.pcd"), cloud);
  writeCloud(dir.file("c.ply"), cloud);
  writeCloud(dir.file("c.xyz"), cloud);
  writeMesh(dir.file("m.stl"), mesh);
  writeMesh(dir.file("m.ply"), mesh);
  writeStlAscii(dir.file("a.stl"), mesh);
  const std::string listing = dir.file("listing");
  ASSERT_EQ(std::system(("ls -a " + dir.file("") + " > " + listing).c_str()), 0);
  const std::string names = readFile(listing);
  EXPECT_EQ(names.find(".tmp"), std::string::npos) << names;
  // An empty cloud (a scan with no finite point) is a valid PCD of no points.
  writeCloud(dir.file("empty.pcd"), PointCloud());
  EXPECT_EQ(readCloud(dir.file("empty.pcd")).size(), 0u);
  // A failed rename (the target is a directory) removes the temporary file, in every format.
  for (const char* name : {"d.pcd", "d.ply", "d.xyz"}) {
    ASSERT_EQ(::mkdir(dir.file(name).c_str(), 0755), 0);
    expectIoError([&] { writeCloud(dir.file(name), cloud); }, dir.file(name),
                  "cannot rename temporary file into place");
  }
  ASSERT_EQ(::mkdir(dir.file("d.stl").c_str(), 0755), 0);
  expectIoError([&] { writeMesh(dir.file("d.stl"), mesh); }, dir.file("d.stl"), "cannot rename");
  ASSERT_EQ(std::system(("ls -a " + dir.file("") + " > " + listing).c_str()), 0);
  EXPECT_EQ(readFile(listing).find(".tmp"), std::string::npos) << readFile(listing);
  // Two temporary names for the same file never collide.
  EXPECT_NE(temporaryPathFor("a"), temporaryPathFor("a"));
}

// Real data in ../shared/data, with the counts its files and README document.
TEST(CloudIoRealData, RoomScans) {
  // "~112.6k points each"; the exact counts are the PCD headers' POINTS.
  for (const auto& [name, count] : {std::pair<const char*, size_t>{"rooms/room_scan1.pcd", 112586},
                                    std::pair<const char*, size_t>{"rooms/room_scan2.pcd", 112624}}) {
    const PointCloud c = readCloud(sharedDataPath(name));
    EXPECT_EQ(c.size(), count) << name;
    EXPECT_EQ(c.countFinite(), c.size()) << name;
  }
}

TEST(CloudIoRealData, BunnyScansAndReference) {
  const std::pair<const char*, size_t> scans[] = {{"bun000.ply", 40256}, {"bun045.ply", 40097},   {"bun090.ply", 30379},
                                                  {"bun180.ply", 40251}, {"bun270.ply", 31701},   {"bun315.ply", 35336},
                                                  {"chin.ply", 37738},   {"ear_back.ply", 32193}, {"top2.ply", 38298},
                                                  {"top3.ply", 36023}};
  for (const auto& s : scans) {
    const PointCloud c = readCloud(sharedDataPath(std::string("bunny/scans/") + s.first));
    EXPECT_EQ(c.size(), s.second) << s.first;
  }
  const TriangleMesh ref = readPly(sharedDataPath("bunny/bun_zipper.ply"));
  EXPECT_EQ(ref.vertices.size(), 35947u);
  EXPECT_EQ(ref.faces.size(), 69451u);
}

TEST(CloudIoRealData, PclTestClouds) {
  EXPECT_EQ(readCloud(sharedDataPath("clouds/bunny.pcd")).size(), 397u);
  const PointCloud bun0 = readCloud(sharedDataPath("clouds/bun0.pcd"));
  EXPECT_EQ(bun0.size(), 397u);
  EXPECT_TRUE(bun0.hasNormals());
  const TriangleMesh cube = readPly(sharedDataPath("clouds/cube.ply"));  // binary little endian
  EXPECT_EQ(cube.vertices.size(), 24u);
  EXPECT_EQ(cube.faces.size(), 12u);
}

// Issue #22 class 6: messages that name the thing. A directory given as an input file said "empty
// file", a missing path without extension "unknown point-cloud format '.'", an output in a missing
// directory PCL's "Error during open!" without a path.
TEST(CloudIo, DirectoriesMissingInputsAndMissingOutputDirectoriesAreNamed) {
  TempDir dir;
  ASSERT_EQ(::mkdir(dir.file("scan.pcd").c_str(), 0755), 0);
  expectIoError([&] { readCloud(dir.file("scan.pcd")); }, dir.file("scan.pcd"), "is a directory, not a file");
  EXPECT_EQ(pcdFileProblem(dir.file("scan.pcd")), "is a directory, not a file");
  expectIoError([&] { readCloud(dir.file("")); }, dir.file(""), "is a directory, not a file");
  expectIoError([&] { readCloud(dir.file("cloud")); }, dir.file("cloud"), "no such file");
  expectIoError([&] { readFile(dir.file("scan.pcd")); }, dir.file("scan.pcd"), "is a directory, not a file");
  PointCloud cloud;
  cloud.push_back({1, 2, 3});
  for (const char* name : {"missing/out.pcd", "missing/out.ply", "missing/out.xyz"})
    expectIoError([&] { writeCloud(dir.file(name), cloud); }, dir.file(name),
                  "cannot write: the directory " + dir.file("missing") + " does not exist");
}

}  // namespace
}  // namespace scanstop
