// The meshing pipeline: voxels, normals towards the scanner, automatic radii, map directory input.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <string>

#include <Eigen/Geometry>
#include <fstream>
#include <sstream>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/shared_data.h"
#include "scanstop_mesher/mesher.h"
#include "synthetic_room.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

using scanstop::test_util::TempDir;

/// Faces whose normal points away from every scanner position (seen from behind). A few slivers
/// in the concave creases where walls meet the floor (whose corners' normals are blends) do.
size_t facesAwayFrom(const TriangleMesh& m, const std::vector<Eigen::Vector3f>& origins) {
  size_t bad = 0;
  for (size_t i = 0; i < m.faces.size(); ++i) {
    const auto& f = m.faces[i];
    const Eigen::Vector3f c = (m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) / 3.0f;
    bool seen = false;
    for (const auto& o : origins) seen = seen || m.faceNormal(i).dot(o - c) > 0;
    bad += !seen;
  }
  return bad;
}

}  // namespace

TEST(Mesher, VoxelDownsampleAveragesEachVoxel) {
  ScanPoints in;
  in.points = {{0.01f, 0.01f, 0.01f}, {0.03f, 0.03f, 0.03f}, {0.51f, 0.0f, 0.0f}};
  in.normals = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}};
  const ScanPoints out = voxelDownsample(in, 0.1);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_TRUE(out.points[0].isApprox(Eigen::Vector3f(0.02f, 0.02f, 0.02f)));
  EXPECT_TRUE(out.normals[0].isApprox(Eigen::Vector3f(0, 1, 1).normalized()));
  EXPECT_EQ(voxelDownsample(in, 0.0).size(), 3u);
  EXPECT_THROW(voxelDownsample(in, 1e-9), ConfigError);
}

TEST(Mesher, MeanSpacingOfAGrid) {
  std::vector<Eigen::Vector3f> grid;
  for (int x = 0; x < 50; ++x)
    for (int y = 0; y < 50; ++y) grid.emplace_back(0.01f * x, 0.01f * y, 0.0f);
  EXPECT_NEAR(meanSpacing(grid), 0.01, 1e-4);
  EXPECT_EQ(meanSpacing({{0, 0, 0}}), 0.0);
  // Every point twice (a real scan repeats points): still the spacing of the surface, not 0.
  std::vector<Eigen::Vector3f> twice = grid;
  twice.insert(twice.end(), grid.begin(), grid.end());
  EXPECT_NEAR(meanSpacing(twice), 0.01, 1e-4);
  const std::vector<double> r = automaticRadii(0.01);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_LT(r[0], r[1]);
  EXPECT_LT(r[1], r[2]);
  EXPECT_GT(r[0], 0.01 / std::sqrt(3.0));  // a ball must span an equilateral triangle of the spacing
  EXPECT_THROW(automaticRadii(0.0), ConfigError);
}

TEST(Mesher, NormalsTurnTowardsTheScannerAndLinesGetNone) {
  ScanPoints pts;
  pts.origins = {{0.5f, 0.5f, 1.0f}, {0.5f, 0.5f, -1.0f}};
  for (int x = 0; x < 20; ++x)
    for (int y = 0; y < 20; ++y) {
      pts.points.emplace_back(0.05f * x, 0.05f * y, 0.0f);
      pts.view.push_back(x < 10 ? 0 : 1);  // left half seen from above, right half from below
    }
  for (int k = 0; k < 10; ++k) {  // a line far away: no plane to fit
    pts.points.emplace_back(5.0f + 0.01f * k, 0.0f, 0.0f);
    pts.view.push_back(0);
  }
  const size_t usable = estimateNormals(pts, 0.11, 5);
  EXPECT_EQ(usable, 400u);
  for (int i = 0; i < 400; ++i) EXPECT_NEAR(pts.normals[i].z(), pts.view[i] == 0 ? 1.0f : -1.0f, 1e-4) << i;
  for (int i = 400; i < 410; ++i) EXPECT_FALSE(pts.normals[i].allFinite());
}

TEST(Mesher, SingleScanOfARoomIsManifoldAndFacesTheScanner) {
  const Eigen::Vector3f origin(-0.5f, 0.3f, 0.5f);
  PointCloud cloud;
  for (const auto& p : test::scanRoom(origin, 180, 360)) cloud.push_back(p);
  MesherConfig config;
  config.voxel_m = 0.06;
  const MesherResult r = buildMesh(fromCloud(cloud, origin), config);
  EXPECT_EQ(r.input_points, cloud.size());
  EXPECT_GT(r.points, 5000u);
  EXPECT_GT(r.mesh.faces.size(), r.points);
  EXPECT_TRUE(r.topology.manifold());
  EXPECT_LT(facesAwayFrom(r.mesh, {origin}), r.mesh.faces.size() / 200);
  EXPECT_EQ(r.radii_m.size(), 3u);
}

TEST(Mesher, MapDirectoryScansAreTransformedAndOrientedPerScan) {
  TempDir tmp("scanstop_mesher_test");
  const std::string dir = tmp.path + "/map";
  const Pose2D poses[2] = {Pose2D(-1.0, 0.5, 0.3), Pose2D(0.5, -1.0, -2.0)};
  std::vector<Eigen::Vector3f> origins;
  size_t total = 0;
  {
    MapDirectory map(dir);
    for (uint32_t s = 0; s < 2; ++s) {
      MapScanInfo info;
      info.index = s;
      info.map_pose = poses[s];
      info.odom_pose = poses[s];
      info.sensor_origin = Eigen::Vector3d(0.1, 0.0, 0.45);
      const Eigen::Isometry3f T_map_base = poses[s].toIsometry3f();
      const Eigen::Vector3f origin = T_map_base * info.sensor_origin.cast<float>();
      origins.push_back(origin);
      PointCloud base;
      for (const auto& p : test::scanRoom(origin, 90, 180, 0.002f, s + 1)) base.push_back(T_map_base.inverse() * p);
      total += base.size();
      map.append(info, base);
    }
  }
  const ScanPoints pts = loadMapDirectory(dir);
  ASSERT_EQ(pts.size(), total);
  ASSERT_EQ(pts.origins.size(), 2u);
  EXPECT_TRUE(pts.origins[1].isApprox(origins[1], 1e-5f));
  const test::Box room = test::roomBounds();
  for (const auto& p : pts.points)  // back in the map frame: on the room's surfaces
    EXPECT_TRUE((p.array() >= room.lo.array() - 0.02f).all() && (p.array() <= room.hi.array() + 0.02f).all());
  MesherConfig config;
  config.voxel_m = 0.08;
  const MesherResult r = buildMesh(pts, config);
  EXPECT_GT(r.mesh.faces.size(), 1000u);
  EXPECT_TRUE(r.topology.manifold());
  EXPECT_LT(facesAwayFrom(r.mesh, origins), r.mesh.faces.size() / 200);
  EXPECT_THROW(loadMapDirectory(tmp.path + "/empty"), IoError);
}

TEST(Mesher, BadSettingsAreNamed) {
  try {
    parseRadii("0.1,abc");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("abc"), std::string::npos);
  }
  try {
    parseRadii("0.2,0.1");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("increase"), std::string::npos);
  }
  EXPECT_EQ(parseRadii("0.01,0.02").size(), 2u);
  MesherConfig c;
  c.voxel_m = -1;
  EXPECT_THROW(c.validate(), ConfigError);
  ScanPoints none;
  EXPECT_THROW(buildMesh(none, MesherConfig()), std::runtime_error);
}

// The ten real range scans of the Stanford bunny, registered with bun.conf (p_common =
// R(q)^T p + t), normals estimated and turned towards each scan's camera (on the scan's +z axis):
// noisy, overlapping input; the mesh stays manifold and on the reference surface.
TEST(Mesher, TenRegisteredBunnyScansStayManifold) {
  const std::string dir = sharedDataPath("bunny/scans/");
  std::ifstream conf(dir + "bun.conf");
  ASSERT_TRUE(conf.good()) << dir << "bun.conf";
  ScanPoints pts;
  std::string line;
  while (std::getline(conf, line)) {
    std::istringstream in(line);
    std::string kind, file;
    float tx, ty, tz, qx, qy, qz, qw;
    if (!(in >> kind >> file >> tx >> ty >> tz >> qx >> qy >> qz >> qw) || kind != "bmesh") continue;
    const Eigen::Quaternionf q(qw, qx, qy, qz);
    const Eigen::Vector3f t(tx, ty, tz);
    pts.origins.push_back(q.conjugate() * Eigen::Vector3f(0, 0, 1) + t);
    for (const auto& p : readPlyCloud(dir + file).points) {
      pts.points.push_back(q.conjugate() * p + t);
      pts.view.push_back(static_cast<uint32_t>(pts.origins.size() - 1));
    }
  }
  ASSERT_EQ(pts.origins.size(), 10u);
  MesherConfig config;
  config.voxel_m = 0.001;
  const MesherResult r = buildMesh(pts, config);
  std::cout << "bunny scans: " << r.input_points << " points -> " << r.points << " meshed, " << r.mesh.faces.size()
            << " triangles in " << r.seconds << " s" << std::endl;
  EXPECT_GT(r.mesh.faces.size(), 30000u);
  EXPECT_EQ(r.topology.nonmanifold_edges, 0u);
  EXPECT_EQ(r.topology.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.topology.inconsistent_edges, 0u);
  const SurfaceDistance d = distanceToSurface(sampleFaces(r.mesh), readPly(sharedDataPath("bunny/bun_zipper.ply")));
  std::cout << "bunny scans: mean distance to the reference " << d.mean_m * 1e3 << " mm" << std::endl;
  EXPECT_LT(d.mean_m, 0.0005);
}
