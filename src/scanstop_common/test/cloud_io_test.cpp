#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/shared_data.h"
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
  const std::string ply = dir.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                               "property float y\nproperty float z\nend_header\n1 2 3\n4 5 6\n");
  expectIoError([&] { readCloud(ply); }, ply, "truncated PLY");
  const std::string notply = dir.write("x.ply", "hello");
  expectIoError([&] { readCloud(notply); }, notply, "not a PLY file");
  const std::string pcd = dir.write("bad.pcd", "this is not a pcd file\n");
  expectIoError([&] { readCloud(pcd); }, pcd, "not a valid PCD file");
  expectIoError([&] { readCloud("/nonexistent/a.pcd"); }, "/nonexistent/a.pcd", "no such file");
  expectIoError([&] { readCloud(dir.file("a.obj")); }, dir.file("a.obj"), "unknown point-cloud format");
  PointCloud broken;
  broken.points.resize(3);
  broken.width = 2;
  expectIoError([&] { writeCloud(dir.file("w.pcd"), broken); }, dir.file("w.pcd"), "inconsistent cloud");
}

TEST(CloudIo, AtomicWriteLeavesNoTemporaryFiles) {
  TempDir dir;
  writeFileAtomic(dir.file("f.txt"), "one");
  writeFileAtomic(dir.file("f.txt"), "two");
  EXPECT_EQ(readFile(dir.file("f.txt")), "two");
  EXPECT_THROW(writeFileAtomic("/nonexistent/dir/f.txt", "x"), IoError);
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
  const std::pair<const char*, size_t> scans[] = {
      {"bun000.ply", 40256}, {"bun045.ply", 40097}, {"bun090.ply", 30379}, {"bun180.ply", 40251},
      {"bun270.ply", 31701}, {"bun315.ply", 35336}, {"chin.ply", 37738},   {"ear_back.ply", 32193},
      {"top2.ply", 38298},   {"top3.ply", 36023}};
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

}  // namespace
}  // namespace scanstop
