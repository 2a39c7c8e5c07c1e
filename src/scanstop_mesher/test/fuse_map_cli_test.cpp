// The fuse_map command-line tool on a small map directory (two scans of the synthetic room): the
// three outputs, the JSON, and bad arguments and maps named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/map_dir.h"
#include "synthetic_room.h"

using namespace scanstop;

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& args) { return scanstop::test_util::runCommand(std::string(FUSE_MAP_EXE) + " " + args); }

/// The number after "key": in a flat JSON object (-1 when missing).
double jsonValue(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return -1;
  return std::stod(json.substr(at + key.size() + 4));
}

using test::writeRoomMap;

/// Distance [m] of a point to the synthetic room's walls, floor, ceiling or box (the nearest).
float offRoom(const Eigen::Vector3f& v) {
  const test::Box room = test::roomBounds(), box = test::roomObstacle();
  float d = 1e9f;
  for (int a = 0; a < 3; ++a) d = std::min({d, std::abs(v[a] - room.lo[a]), std::abs(v[a] - room.hi[a])});
  const Eigen::Vector3f q = v.cwiseMax(box.lo).cwiseMin(box.hi);
  return std::min(d, (q - v).norm());
}

}  // namespace

TEST(FuseMapCli, FusesAMapDirectoryIntoThreeOutputs) {
  TempDir tmp("fuse_map_cli_test");
  writeRoomMap(tmp.path + "/map");
  CliRun r = run(tmp.path + "/map " + tmp.path + "/mc.ply --decimate 0 --json --vdb " + tmp.path + "/map.vdb");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << "one line: " << r.out;
  EXPECT_EQ(jsonValue(r.out, "scans"), 2);
  EXPECT_EQ(jsonValue(r.out, "points"), 667200);
  EXPECT_GT(jsonValue(r.out, "observed_voxels"), 100000);
  EXPECT_GT(jsonValue(r.out, "memory_bytes"), 1e6);
  const double triangles = jsonValue(r.out, "triangles");
  EXPECT_GT(triangles, 500000);
  EXPECT_EQ(jsonValue(r.out, "nonmanifold_edges"), 0);
  EXPECT_EQ(jsonValue(r.out, "nonmanifold_vertices"), 0);
  const TriangleMesh mc = readMesh(tmp.path + "/mc.ply");
  EXPECT_EQ(static_cast<double>(mc.faces.size()), triangles);
  EXPECT_EQ(mc.normals.size(), mc.vertices.size());
  // Every vertex lies on the room's walls, floor, ceiling or the box (within a voxel).
  size_t off = 0;
  float worst = 0.0f;
  Eigen::Vector3f worst_at = Eigen::Vector3f::Zero();
  for (const auto& v : mc.vertices) {
    const float d = offRoom(v);
    off += d > 0.02f;
    if (d > worst) {
      worst = d;
      worst_at = v;
    }
  }
  std::printf(
      "marching cubes: %zu of %zu vertices more than 2 cm off the room; the worst %.1f mm at (%.2f, %.2f, %.2f)\n", off,
      mc.vertices.size(), 1e3 * worst, worst_at.x(), worst_at.y(), worst_at.z());
  // Only at the box's convex edges (TSDF rounds them: beams passing the edge see through its cells).
  EXPECT_LT(off, mc.vertices.size() / 1000);
  EXPECT_LT(worst, 0.03f);
  std::ifstream vdb(tmp.path + "/map.vdb", std::ios::binary | std::ios::ate);
  EXPECT_GT(static_cast<long>(vdb.tellg()), 100000);

  // By default the mesh is decimated within 2 mm: far fewer triangles on the room's flat faces, the
  // vertices still on them.
  r = run(tmp.path + "/map " + tmp.path + "/decimated.ply --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(jsonValue(r.out, "decimated_from"), triangles);
  const TriangleMesh dec = readMesh(tmp.path + "/decimated.ply");
  EXPECT_EQ(static_cast<double>(dec.faces.size()), jsonValue(r.out, "triangles"));
  EXPECT_LT(static_cast<double>(dec.faces.size()), triangles / 5);
  EXPECT_EQ(jsonValue(r.out, "nonmanifold_edges"), 0);
  size_t dec_off = 0;
  for (const auto& v : dec.vertices) dec_off += offRoom(v) > 0.02f;
  std::printf("decimated: %zu of %zu triangles; %zu of %zu vertices more than 2 cm off the room\n", dec.faces.size(),
              static_cast<size_t>(triangles), dec_off, dec.vertices.size());
  EXPECT_LT(dec_off, dec.vertices.size() / 200);

  r = run(tmp.path + "/map " + tmp.path + "/points.ply --mesh points");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("points with normals"), std::string::npos) << r.out;
  const PointCloud points = readCloud(tmp.path + "/points.ply");
  EXPECT_GT(points.size(), 200000u);
  EXPECT_EQ(points.normals.size(), points.size());

  r = run(tmp.path + "/map " + tmp.path + "/bpa.stl --mesh bpa --voxel 0.05 --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_GT(jsonValue(r.out, "triangles"), 10000);
  EXPECT_EQ(static_cast<double>(readMesh(tmp.path + "/bpa.stl").faces.size()), jsonValue(r.out, "triangles"));
}

TEST(FuseMapCli, AMapTooLargeForTheBoundIsMeshedInSlabs) {
  TempDir tmp("fuse_map_cli_test");
  writeRoomMap(tmp.path + "/map");
  CliRun whole = run(tmp.path + "/map " + tmp.path + "/whole.ply --carve 0.2 --json");
  ASSERT_EQ(whole.status, 0) << whole.out;
  EXPECT_EQ(jsonValue(whole.out, "slabs"), 1);
  CliRun r = run(tmp.path + "/map " + tmp.path + "/slabs.ply --carve 0.2 --max-grid-mb 20 --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_GT(jsonValue(r.out, "slabs"), 1) << r.out;
  EXPECT_LE(jsonValue(r.out, "memory_bytes"), 20.0 * 1048576) << r.out;
  EXPECT_EQ(static_cast<double>(readMesh(tmp.path + "/slabs.ply").faces.size()), jsonValue(r.out, "triangles"));
  // Each slab's mesh decimated alone: from the whole map's faces (counted before the pinched fans at the
  // rim are dropped over the welded mesh).
  EXPECT_GE(jsonValue(r.out, "decimated_from"), jsonValue(whole.out, "decimated_from")) << r.out;
  EXPECT_LE(jsonValue(r.out, "decimated_from"), 1.01 * jsonValue(whole.out, "decimated_from")) << r.out;
  EXPECT_EQ(jsonValue(r.out, "nonmanifold_edges"), 0);
  r = run(tmp.path + "/map " + tmp.path + "/points.ply --mesh points --carve 0.2 --max-grid-mb 20");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("in slabs along x only a mesh without --vdb is built"), std::string::npos) << r.out;
}

TEST(FuseMapCli, BadArgumentsAndMapsAreNamed) {
  TempDir tmp("fuse_map_cli_test");
  CliRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: fuse_map", 0), 0u) << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.ply --voxel 0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("fuse_map: --voxel 0: not a number in [0.001, 1]"), std::string::npos) << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.ply --truncation 0.03");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("truncation_m"), std::string::npos) << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.stl --mesh points");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("x.stl"), std::string::npos) << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.ply --mesh voxels");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--mesh voxels"), std::string::npos) << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.ply --radii 0.05");
  EXPECT_EQ(r.status, 2);
  r = run(tmp.path + " " + tmp.path + "/x.ply");  // a directory that is no map
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/poses.csv: does not exist"), std::string::npos) << r.out;
  r = run(tmp.path + " " + tmp.path + "/no_dir/x.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/no_dir/x.ply: cannot write"), std::string::npos) << r.out;

  writeRoomMap(tmp.path + "/map");
  ASSERT_EQ(std::remove((tmp.path + "/map/scans/scan_0001.pcd").c_str()), 0);
  r = run(tmp.path + "/map " + tmp.path + "/m.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/map/scans/scan_0001.pcd: no such file"), std::string::npos) << r.out;
  EXPECT_FALSE(std::ifstream(tmp.path + "/m.ply").good());
  r = run(tmp.path + "/map " + tmp.path + "/m.ply --skip-bad --json");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("fuse_map: warning: skipped: " + tmp.path + "/map/scans/scan_0001.pcd"), std::string::npos)
      << r.out;
  EXPECT_TRUE(std::ifstream(tmp.path + "/m.ply").good());
}
