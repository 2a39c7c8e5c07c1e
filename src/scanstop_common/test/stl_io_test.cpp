#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
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

/// A unit tetrahedron, outward winding.
TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

void expectSameTriangles(const TriangleMesh& expected, const TriangleMesh& soup) {
  ASSERT_EQ(soup.faces.size(), expected.faces.size());
  ASSERT_EQ(soup.vertices.size(), 3 * expected.faces.size());
  for (size_t f = 0; f < expected.faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(soup.vertices[soup.faces[f][k]].isApprox(expected.vertices[expected.faces[f][k]]))
          << "face " << f << " corner " << k;
}

std::string binaryStl(uint32_t announced, size_t actual, float value = 0.5f) {
  std::string s(80, ' ');
  s.append(reinterpret_cast<const char*>(&announced), 4);
  for (size_t i = 0; i < actual; ++i) {
    for (int k = 0; k < 12; ++k) s.append(reinterpret_cast<const char*>(&value), 4);
    s.append(2, '\0');
  }
  return s;
}

TEST(Stl, BinaryRoundTrip) {
  TempDir dir;
  const TriangleMesh mesh = tetrahedron();
  writeStlBinary(dir.file("t.stl"), mesh);
  expectSameTriangles(mesh, readStl(dir.file("t.stl")));
}

TEST(Stl, AsciiRoundTrip) {
  TempDir dir;
  const TriangleMesh mesh = tetrahedron();
  writeStlAscii(dir.file("t.stl"), mesh);
  EXPECT_EQ(readFile(dir.file("t.stl")).compare(0, 5, "solid"), 0);
  const TriangleMesh back = readStl(dir.file("t.stl"));
  expectSameTriangles(mesh, back);
  // Face normals from the winding point outwards (away from the centroid).
  const Eigen::Vector3f centroid(0.25f, 0.25f, 0.25f);
  for (size_t f = 0; f < back.faces.size(); ++f)
    EXPECT_GT(back.faceNormal(f).dot(back.vertices[back.faces[f][0]] - centroid), 0.0f);
}

TEST(Stl, BinaryHeaderStartingWithSolidIsStillBinary) {
  TempDir dir;
  std::string data = binaryStl(2, 2);
  data.replace(0, 11, "solid facet");
  const TriangleMesh m = parseStl(data, "x.stl");
  EXPECT_EQ(m.faces.size(), 2u);
}

TEST(Stl, MissingFile) {
  expectIoError([] { readStl("/nonexistent/world.stl"); }, "/nonexistent/world.stl", "no such file");
}

TEST(Stl, EmptyFile) {
  TempDir dir;
  const std::string p = dir.write("empty.stl", "");
  expectIoError([&] { readStl(p); }, p, "empty file");
}

TEST(Stl, ZeroTriangles) {
  TempDir dir;
  const std::string p = dir.write("zero.stl", binaryStl(0, 0));
  expectIoError([&] { readStl(p); }, p, "no triangles");
  const std::string q = dir.write("zero_ascii.stl", "solid x\nendsolid x\n");
  expectIoError([&] { readStl(q); }, q, "no triangles");
}

TEST(Stl, TruncatedBinary) {
  TempDir dir;
  std::string data = binaryStl(10, 10);
  data.resize(data.size() - 7);
  const std::string p = dir.write("truncated.stl", data);
  expectIoError([&] { readStl(p); }, p, "truncated binary STL");
}

TEST(Stl, WrongTriangleCount) {
  TempDir dir;
  const std::string p = dir.write("count.stl", binaryStl(3, 5));
  expectIoError([&] { readStl(p); }, p, "announces 3 triangles");
}

TEST(Stl, NaNCoordinates) {
  TempDir dir;
  const std::string p = dir.write("nan.stl", binaryStl(2, 2, std::numeric_limits<float>::quiet_NaN()));
  expectIoError([&] { readStl(p); }, p, "triangle 0 has a non-finite");
  const std::string q = dir.write("nan_ascii.stl",
                                  "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                  "vertex nan 1 0\nendloop\nendfacet\nendsolid x\n");
  expectIoError([&] { readStl(q); }, q, "non-finite");
}

// Issue #22 class 3: one vertex at 1e30 m ended floor_coverage in an OpenCV assertion.
TEST(Stl, AbsurdCoordinatesAreRefusedByTriangleAndVertex) {
  TempDir dir;
  TriangleMesh mesh = tetrahedron();
  mesh.vertices[3] = Eigen::Vector3f(0, 1e30f, 0);
  writeStlBinary(dir.file("far.stl"), mesh);
  expectIoError([&] { readStl(dir.file("far.stl")); }, dir.file("far.stl"),
                "triangle 1 vertex 3 (0, 1e+30, 0) lies beyond the 100000 m coordinate limit");
  const std::string q = dir.write("far_ascii.stl",
                                  "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                  "vertex 0 -2e5 0\nendloop\nendfacet\nendsolid x\n");
  expectIoError([&] { readStl(q); }, q,
                "triangle 0 vertex 3 (0, -200000, 0) lies beyond the 100000 m coordinate limit");
  mesh.vertices[3] = Eigen::Vector3f(0, 99999, 0);  // inside the limit: read
  writeStlBinary(dir.file("near.stl"), mesh);
  EXPECT_EQ(readStl(dir.file("near.stl")).faces.size(), 4u);
}

// Issue #22 class 6: a directory read as a file said "empty file".
TEST(Stl, ADirectoryIsNamedAsADirectory) {
  TempDir dir;
  expectIoError([&] { readStl(dir.file("")); }, dir.file(""), "is a directory, not a file");
  expectIoError([&] { readMesh(dir.file("")); }, dir.file(""), "is a directory, not a file");
}

TEST(Stl, NotAnStl) {
  TempDir dir;
  const std::string p = dir.write("readme.stl", std::string(200, 'a') + "\nThis is a README, not a mesh.\n");
  expectIoError([&] { readStl(p); }, p, "not an STL file");
  const std::string q = dir.write("short.stl", "hello");
  expectIoError([&] { readStl(q); }, q, "not an STL file");
}

TEST(Stl, MalformedAscii) {
  TempDir dir;
  const std::string p = dir.write("bad.stl",
                                  "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                  "endloop\nendfacet\nendsolid x\n");
  expectIoError([&] { readStl(p); }, p, "exactly three vertices");
  const std::string q = dir.write("bad2.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 zero 0\n");
  expectIoError([&] { readStl(q); }, q, "not a number");
}

TEST(Stl, RealHouseWorld) {
  const std::string path = sharedDataPath("worlds/turtlebot3_house.stl");
  const TriangleMesh m = readStl(path);
  const std::string data = readFile(path);
  uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, 4);
  EXPECT_EQ(m.faces.size(), count);
  EXPECT_GT(count, 100u);
  // The data README: a house of 15.2 x 10.7 x 2.5 m (the walls) with a floor rectangle added at z = 0.
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f), hi = -lo;
  float z_min = 1e9f;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    bool flat_floor = true;
    for (int k = 0; k < 3; ++k) flat_floor = flat_floor && std::abs(m.vertices[m.faces[f][k]].z()) < 1e-4f;
    for (int k = 0; k < 3; ++k) z_min = std::min(z_min, m.vertices[m.faces[f][k]].z());
    if (flat_floor) continue;
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(m.vertices[m.faces[f][k]]);
      hi = hi.cwiseMax(m.vertices[m.faces[f][k]]);
    }
  }
  EXPECT_NEAR(hi.x() - lo.x(), 15.2f, 0.2f);
  EXPECT_NEAR(hi.y() - lo.y(), 10.7f, 0.2f);
  EXPECT_NEAR(hi.z(), 2.5f, 0.1f);
  EXPECT_NEAR(z_min, 0.0f, 1e-4f);
}

}  // namespace
}  // namespace scanstop
