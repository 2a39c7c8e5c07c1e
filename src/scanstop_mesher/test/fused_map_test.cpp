// The fused TSDF map (issue #20): free-space carving, noise averaging on a plane, Marching Cubes of
// a sphere (closed, manifold, within the voxel tolerance), unseen space stays a hole, a map directory
// meshed by either fused method.
#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/error.h"
#include "scanstop_mesher/fused_map.h"
#include "scanstop_mesher/mesh_analysis.h"
#include "synthetic_room.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Readings from `origin` of the wall x = wall_x at the targets (y, z) of a grid over
/// [y0, y1] x [z0, z1] with the given spacing, each range perturbed by Gaussian noise of sigma [m].
std::vector<Eigen::Vector3f> scanWall(const Eigen::Vector3f& origin, double wall_x, double y0, double y1, double z0,
                                      double z1, double spacing, double sigma, std::mt19937& rng, double jitter = 0.0) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> shift(0.0, jitter);
  const double sy = shift(rng), sz = shift(rng);
  std::vector<Eigen::Vector3f> out;
  for (double y = y0 + sy; y <= y1; y += spacing) {
    for (double z = z0 + sz; z <= z1; z += spacing) {
      const Eigen::Vector3d o = origin.cast<double>();
      const Eigen::Vector3d hit(wall_x, y, z);
      const Eigen::Vector3d d = (hit - o).normalized();
      const double r = (hit - o).norm() + (sigma > 0 ? sigma * noise(rng) : 0.0);
      out.push_back((o + r * d).cast<float>());
    }
  }
  return out;
}

size_t countNear(const std::vector<Eigen::Vector3f>& pts, const Eigen::Vector3f& c, float radius) {
  size_t n = 0;
  for (const auto& p : pts) n += (p - c).norm() < radius;
  return n;
}

}  // namespace

TEST(FusedMap, ConfigAndOriginAreChecked) {
  FusedMapConfig c;
  c.truncation_m = 0.03;  // less than two voxels of 0.02
  try {
    FusedMap m(c);
    FAIL() << "accepted truncation_m 0.03 with voxel_m 0.02";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("truncation_m"), std::string::npos) << e.what();
  }
  c = FusedMapConfig();
  c.min_weight = 0.5;
  EXPECT_THROW(FusedMap{c}, ConfigError);
  FusedMap m;
  EXPECT_THROW(m.integrate({Eigen::Vector3f(1, 0, 0)}, Eigen::Vector3f(kNaN, 0, 0)), ConfigError);
  // NaN readings (the scanner's invalid ones) and a reading at the origin are skipped.
  EXPECT_EQ(m.integrate({Eigen::Vector3f(kNaN, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f::Zero()},
                        Eigen::Vector3f::Zero()),
            1u);
  EXPECT_EQ(m.stats().skipped_points, 2u);
  EXPECT_EQ(m.stats().points, 1u);
  // The beam from 0 to x = 1: free before the band, the hit's voxel near 0, behind it negative.
  EXPECT_FLOAT_EQ(m.distanceAt(Eigen::Vector3f(0.5f, 0, 0)), 0.06f);
  EXPECT_NEAR(m.distanceAt(Eigen::Vector3f(1.0f, 0, 0)), 0.0f, 1e-6);
  EXPECT_NEAR(m.distanceAt(Eigen::Vector3f(1.04f, 0, 0)), -0.04f, 1e-6);
  EXPECT_EQ(m.weightAt(Eigen::Vector3f(1.1f, 0, 0)), 0.0f);  // beyond the band: never updated
  EXPECT_EQ(m.weightAt(Eigen::Vector3f(0.5f, 0, 0)), 1.0f);
}

// Issue #22 class 3: a voxel far too fine for the scans (1 mm on a wall 3 m away, whole beams carved)
// wanted 9 GB and more; with max_grid_mb the integration ends at the bound, naming the voxel.
TEST(FusedMap, AVoxelTooFineForTheMapEndsAtMaxGridMbNamingIt) {
  std::mt19937 rng(3);
  const std::vector<Eigen::Vector3f> wall = scanWall(Eigen::Vector3f::Zero(), 3.0, -1, 1, -1, 1, 0.02, 0.0, rng);
  FusedMapConfig fine;
  fine.voxel_m = 0.001;
  fine.truncation_m = 0.003;
  fine.max_grid_mb = 20;
  FusedMap m(fine);
  try {
    m.integrate(wall, Eigen::Vector3f::Zero());
    FAIL() << "integrated " << m.memoryBytes() / 1048576.0 << " MB of grids past max_grid_mb 20";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_grid_mb = 20 MB"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("voxel_m = 0.001 m is too fine"), std::string::npos) << e.what();
  }
  // It stopped at the bound (the grids' own count adds their internal nodes: 25 MB measured).
  EXPECT_LT(m.memoryBytes(), 30u * 1048576u);
  EXPECT_GT(m.memoryBytes(), 19u * 1048576u);
  // The default voxel holds the same wall within the default bound.
  FusedMap ok;
  EXPECT_EQ(ok.integrate(wall, Eigen::Vector3f::Zero()), wall.size());
  EXPECT_LT(ok.memoryBytes(), FusedMapConfig().max_grid_mb * 1048576.0);
  fine.max_grid_mb = 0;  // below the allowed range
  EXPECT_THROW(FusedMap{fine}, ConfigError);
}

// A spurious reading (here a small dense cluster, as a person walking by) that two later scans see
// through disappears from the fused surface; without carving it stays (the control).
TEST(FusedMap, FreeSpaceCarvingRemovesWhatLaterScansSeeThrough) {
  const Eigen::Vector3f a(0, 0, 0), b(0, 0.4f, 0.1f), c(0, -0.4f, -0.1f), spurious(1.507f, 0, 0);
  std::mt19937 rng(1);
  // The first scan: the wall, but for the 6 cm x 6 cm spurious patch in front of it, which hides
  // the wall behind it (the beams towards |y|, |z| < 0.07 at the wall end on the patch).
  std::vector<Eigen::Vector3f> first;
  for (const auto& p : scanWall(a, 3.0, -0.5, 0.5, -0.5, 0.5, 0.01, 0.0, rng))
    if (std::abs(p.y()) > 0.07f || std::abs(p.z()) > 0.07f) first.push_back(p);
  for (double y = -0.03; y <= 0.03; y += 0.005)
    for (double z = -0.03; z <= 0.03; z += 0.005) first.emplace_back(spurious.x(), y, z);
  // Later scans: beams through a 20 cm square around the spurious reading, on to the wall.
  const auto through = [&](const Eigen::Vector3f& o) {
    std::vector<Eigen::Vector3f> out = scanWall(o, 3.0, -0.5, 0.5, -0.5, 0.5, 0.01, 0.0, rng);
    for (double y = -0.1; y <= 0.1; y += 0.005) {
      for (double z = -0.1; z <= 0.1; z += 0.005) {
        const Eigen::Vector3f q = spurious + Eigen::Vector3f(0, y, z);
        out.push_back(o + (q - o) * ((3.0f - o.x()) / (q.x() - o.x())));
      }
    }
    return out;
  };
  const std::vector<Eigen::Vector3f> second = through(b), third = through(c);

  FusedMapConfig no_carving;
  no_carving.carve_m = 0.0;
  FusedMap carved, kept(no_carving);
  for (FusedMap* m : {&carved, &kept}) m->integrate(first, a);
  EXPECT_GE(countNear(carved.surfacePoints().points, spurious, 0.1f), 4u);
  for (FusedMap* m : {&carved, &kept}) {
    m->integrate(second, b);
    m->integrate(third, c);
  }
  const ScanPoints with = carved.surfacePoints(), without = kept.surfacePoints();
  EXPECT_EQ(countNear(with.points, spurious, 0.1f), 0u);
  EXPECT_GE(countNear(without.points, spurious, 0.1f), 4u);  // the control: no carving, it stays
  // The wall itself is not carved away: as many wall points with carving as without.
  size_t wall_with = 0, wall_without = 0;
  for (const auto& p : with.points) wall_with += std::abs(p.x() - 3.0f) < 0.01f;
  for (const auto& p : without.points) wall_without += std::abs(p.x() - 3.0f) < 0.01f;
  EXPECT_GT(wall_without, 2000u);
  EXPECT_GE(wall_with, wall_without * 99 / 100);

  // The spurious patch lies 1.5 m before the later scans' hits: 0.2 m of carving does not reach it;
  // the far carving pass (carve_far: the rest of each beam, in voxels that exist) removes it, and
  // leaves the wall as the whole beam does.
  FusedMapConfig near_only;
  near_only.carve_m = 0.2;
  FusedMapConfig far = near_only;
  far.carve_far = true;
  FusedMap short_carve(near_only), far_carve(far);
  for (FusedMap* m : {&short_carve, &far_carve}) {
    m->integrate(first, a);
    m->integrate(second, b);
    m->integrate(third, c);
  }
  EXPECT_GT(far_carve.carveFar(first, a) + far_carve.carveFar(second, b) + far_carve.carveFar(third, c), 100u);
  EXPECT_GE(countNear(short_carve.surfacePoints().points, spurious, 0.1f), 4u);  // the control
  const ScanPoints far_points = far_carve.surfacePoints();
  EXPECT_EQ(countNear(far_points.points, spurious, 0.1f), 0u);
  size_t wall_far = 0;
  for (const auto& p : far_points.points) wall_far += std::abs(p.x() - 3.0f) < 0.01f;
  EXPECT_GE(wall_far, wall_without * 99 / 100);
}

// 20 scans of a plane from different origins, Gaussian range noise of 1 cm along the beam: the
// fused surface points lie within 1 mm RMS of the plane (every surface point counted, also those at
// the edge of the seen patch), unbiased, with normals towards the scanners.
TEST(FusedMap, PlaneFromTwentyNoisyScansIsWithinAMillimetre) {
  FusedMapConfig config;
  config.carve_m = 0.1;  // the noise never reaches the carved part; keeps the test fast
  FusedMap map(config);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0.5, 1.5), uyz(-0.5, 0.5);
  const double wall_x = 3.007;  // not on a voxel centre
  for (int s = 0; s < 20; ++s) {
    const Eigen::Vector3f o(ux(rng), uyz(rng), uyz(rng));
    map.integrate(scanWall(o, wall_x, -0.8, 0.8, -0.8, 0.8, 0.005, 0.01, rng, 0.005), o);
  }
  const ScanPoints sp = map.surfacePoints();
  ASSERT_GT(sp.size(), 6000u);  // one per 2 cm cell of the 1.6 m x 1.6 m patch: about 6400
  ASSERT_LT(sp.size(), 6800u);
  double sum = 0.0, sum_abs = 0.0, sum_sq = 0.0, max_abs = 0.0;
  size_t bad_normals = 0;
  for (size_t i = 0; i < sp.size(); ++i) {
    const double d = sp.points[i].x() - wall_x;
    sum += d;
    sum_abs += std::abs(d);
    sum_sq += d * d;
    max_abs = std::max(max_abs, std::abs(d));
    bad_normals += sp.normals[i].dot(Eigen::Vector3f(-1, 0, 0)) < 0.98f;
  }
  const double n = static_cast<double>(sp.size());
  const double rms = std::sqrt(sum_sq / n);
  std::printf("plane: %zu surface points, signed mean %.3f mm, mean |d| %.3f mm, RMS %.3f mm, max %.3f mm\n", sp.size(),
              1e3 * sum / n, 1e3 * sum_abs / n, 1e3 * rms, 1e3 * max_abs);
  EXPECT_LT(rms, 0.001);                 // the target: within 1 mm (RMS)
  EXPECT_LT(std::abs(sum / n), 0.0003);  // no bias
  EXPECT_LT(max_abs, 0.006);
  EXPECT_LT(bad_normals, sp.size() / 100);
  // One noisy scan alone is far worse: the averaging is what gets below the millimetre.
  FusedMap single(config);
  const Eigen::Vector3f o(1.0f, 0.0f, 0.0f);
  single.integrate(scanWall(o, wall_x, -0.8, 0.8, -0.8, 0.8, 0.005, 0.01, rng, 0.005), o);
  single.integrate(scanWall(o, wall_x, -0.8, 0.8, -0.8, 0.8, 0.005, 0.01, rng, 0.005), o);
  double single_sq = 0.0;
  const ScanPoints ss = single.surfacePoints();
  for (const auto& p : ss.points) single_sq += (p.x() - wall_x) * (p.x() - wall_x);
  EXPECT_GT(std::sqrt(single_sq / ss.size()), 1.5 * rms);
}

namespace {

/// Noise-free readings of a sphere from an origin: beams on an angular grid around the direction
/// to the centre; misses are NaN (as the scanner's invalid readings).
std::vector<Eigen::Vector3f> scanSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& centre, double radius,
                                        double half_angle, double step, size_t* hits) {
  const Eigen::Vector3d w = (centre - o).normalized();
  const Eigen::Vector3d u = w.unitOrthogonal(), v = w.cross(u);
  std::vector<Eigen::Vector3f> out;
  for (double a = -half_angle; a <= half_angle; a += step) {
    for (double b = -half_angle; b <= half_angle; b += step) {
      const Eigen::Vector3d d = (w + std::tan(a) * u + std::tan(b) * v).normalized();
      const Eigen::Vector3d oc = o - centre;
      const double bq = oc.dot(d), cq = oc.squaredNorm() - radius * radius, disc = bq * bq - cq;
      if (disc < 0) {
        out.emplace_back(kNaN, kNaN, kNaN);
        continue;
      }
      out.push_back((o + (-bq - std::sqrt(disc)) * d).cast<float>());
      ++*hits;
    }
  }
  return out;
}

}  // namespace

// A sphere scanned from the 6 axis directions and the 8 corners: Marching Cubes (volumeToMesh) gives
// one closed, manifold surface of genus 0, faces turned outwards, every vertex within a fifth of a
// voxel of the sphere.
TEST(FusedMap, MarchingCubesOfASphereIsClosedManifoldAndAccurate) {
  FusedMapConfig config;
  config.carve_m = 0.2;
  FusedMap map(config);
  const Eigen::Vector3d centre(0.013, -0.007, 0.021);
  const double radius = 0.5;
  size_t hits = 0, readings = 0, integrated = 0;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const int nonzero = (dx != 0) + (dy != 0) + (dz != 0);
        if (nonzero != 1 && nonzero != 3) continue;
        const Eigen::Vector3d o = centre + 2.0 * Eigen::Vector3d(dx, dy, dz).normalized();
        const std::vector<Eigen::Vector3f> scan = scanSphere(o, centre, radius, 0.3, 0.004, &hits);
        readings += scan.size();
        integrated += map.integrate(scan, o.cast<float>());
      }
    }
  }
  EXPECT_EQ(integrated, hits);
  EXPECT_EQ(map.stats().skipped_points, readings - hits);  // the NaN misses
  const TriangleMesh mesh = map.extractMesh();
  const MeshTopology t = analyzeTopology(mesh);
  std::printf("sphere: %zu vertices, %zu faces, %zu boundary edges, %zu components, Euler %ld, %zu voxels, %zu bytes\n",
              t.vertices, t.faces, t.boundary_edges, t.components, t.euler(), map.activeVoxels(), map.memoryBytes());
  ASSERT_GT(t.faces, 5000u);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_TRUE(t.manifold()) << t.nonmanifold_edges << " non-manifold edges, " << t.nonmanifold_vertices
                            << " non-manifold vertices, " << t.inconsistent_edges << " inconsistent edges";
  EXPECT_EQ(t.degenerate_faces, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler(), 2);
  double max_err = 0.0, sum_err = 0.0;
  for (const auto& v : mesh.vertices) {
    const double e = std::abs((v.cast<double>() - centre).norm() - radius);
    max_err = std::max(max_err, e);
    sum_err += e;
  }
  std::printf("sphere: vertex distance to the sphere mean %.3f mm, max %.3f mm\n", 1e3 * sum_err / mesh.vertices.size(),
              1e3 * max_err);
  EXPECT_LT(max_err, 0.2 * config.voxel_m);
  size_t inward = 0, bad_normals = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& tri = mesh.faces[f];
    const Eigen::Vector3f centroid = (mesh.vertices[tri[0]] + mesh.vertices[tri[1]] + mesh.vertices[tri[2]]) / 3.0f;
    inward += mesh.faceNormal(f).dot(centroid - centre.cast<float>()) <= 0.0f;
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    bad_normals += mesh.normals[i].dot((mesh.vertices[i] - centre.cast<float>()).normalized()) < 0.98f;
  EXPECT_EQ(inward, 0u);
  EXPECT_EQ(bad_normals, 0u);

  // The surface points lie on the sphere too.
  const ScanPoints sp = map.surfacePoints();
  double sp_max = 0.0;
  for (const auto& p : sp.points) sp_max = std::max(sp_max, std::abs((p.cast<double>() - centre).norm() - radius));
  EXPECT_GT(sp.size(), 2000u);
  EXPECT_LT(sp_max, 0.2 * config.voxel_m);
}

// A wall seen only on its half y >= 0: the mesh covers that half and nothing else; no surface is
// invented where nothing was seen (neither on the unseen half nor behind the wall, where the band
// meets unobserved space).
TEST(FusedMap, UnobservedSpaceStaysAHole) {
  FusedMap map;
  std::mt19937 rng(3);
  for (const Eigen::Vector3f& o : {Eigen::Vector3f(0, 0.5f, 0), Eigen::Vector3f(0.2f, 0.2f, 0.1f)})
    map.integrate(scanWall(o, 3.0, 0.0, 1.0, -0.5, 0.5, 0.01, 0.0, rng), o);
  const TriangleMesh mesh = map.extractMesh();
  ASSERT_GT(mesh.faces.size(), 1000u);
  double area = 0.0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
  }
  float y_min = 1e9f, y_max = -1e9f, off_plane = 0.0f;
  for (const auto& v : mesh.vertices) {
    y_min = std::min(y_min, v.y());
    y_max = std::max(y_max, v.y());
    off_plane = std::max(off_plane, std::abs(v.x() - 3.0f));
  }
  std::printf("half wall: %zu faces, area %.3f m2, y in [%.3f, %.3f], max off the plane %.2f mm\n", mesh.faces.size(),
              area, y_min, y_max, 1e3 * off_plane);
  EXPECT_GT(y_min, -0.02f);  // nothing on the unseen half
  EXPECT_LT(y_max, 1.02f);
  EXPECT_LT(off_plane, 0.001f);  // no surface behind the wall
  EXPECT_GT(area, 0.9);          // the seen half (1 m x 1 m) is covered, less a voxel-wide rim
  EXPECT_LT(area, 1.0);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.boundary_loops, 1u);
}

// Beams 5 cm apart at the wall (a far wall, sparse planes) with 2 cm voxels: crossed voxels alone
// (splat 0) leave the band full of gaps and the mesh in pieces; the 3 x 3 splat closes it.
TEST(FusedMap, SplatClosesTheGapsBetweenSparseBeams) {
  std::mt19937 rng(5);
  FusedMapConfig thick;
  thick.splat = 1;
  FusedMap sparse, splatted(thick);
  for (const Eigen::Vector3f& o : {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0.3f, 0.4f, 0.1f)}) {
    const std::vector<Eigen::Vector3f> scan = scanWall(o, 3.011, -0.5, 0.5, -0.5, 0.5, 0.05, 0.0, rng, 0.05);
    sparse.integrate(scan, o);
    splatted.integrate(scan, o);
  }
  const MeshTopology t0 = analyzeTopology(sparse.extractMesh()), t1 = analyzeTopology(splatted.extractMesh());
  std::printf(
      "sparse beams: splat 0: %zu faces, %zu components; splat 1: %zu faces, %zu components, %zu boundary loops\n",
      t0.faces, t0.components, t1.faces, t1.components, t1.boundary_loops);
  EXPECT_LT(t0.faces, t1.faces / 2);
  EXPECT_EQ(t1.components, 1u);
  EXPECT_EQ(t1.boundary_loops, 1u);
  EXPECT_TRUE(t1.manifold());
  EXPECT_GT(t1.faces, 3500u);  // the 1 m x 1 m wall: 2500 cells of 2 cm, two triangles each, less the rim
}

namespace {

/// Distance [m] from p to the synthetic room's surfaces (its inner faces and the box on the floor).
float roomSurfaceDistance(const Eigen::Vector3f& p) {
  const test::Box room = test::roomBounds(), box = test::roomObstacle();
  const float to_room = std::min((p - room.lo).minCoeff(), (room.hi - p).minCoeff());
  const Eigen::Vector3f outside = (box.lo - p).cwiseMax(p - box.hi).cwiseMax(0.0f);
  const float inside = std::min((p - box.lo).minCoeff(), (box.hi - p).minCoeff());
  const float to_box = outside.norm() > 0.0f ? outside.norm() : inside;
  return std::min(std::abs(to_room), to_box);
}

}  // namespace

TEST(FusedMap, AMapDirectoryIsMeshedByEitherFusedMethod) {
  // bpa_mesher_node's mesh_method: two scans of the synthetic room (5 mm noise) through the fused
  // map, by Marching Cubes and by Ball Pivoting of its surface points; the vertices lie on the
  // room's surfaces (the TSDF rounds the box's convex edges by up to about 2 cm: a few vertices).
  test_util::TempDir tmp("fused_map_test");
  test::writeRoomMap(tmp.path + "/map");
  FusedMapConfig config;
  config.carve_m = 0.2;
  for (const std::string method : {"marching_cubes", "fused_bpa"}) {
    const FusedMesh m = meshFusedMapDirectory(tmp.path + "/map", config, method, MesherConfig());
    EXPECT_EQ(m.scans, 2u) << method;
    EXPECT_GT(m.mesh.faces.size(), 50000u) << method;
    EXPECT_GT(m.voxels, 100000u) << method;
    size_t off = 0;
    double sum = 0.0;
    for (const auto& v : m.mesh.vertices) {
      const float d = roomSurfaceDistance(v);
      sum += d;
      off += d > 0.02f ? 1 : 0;
    }
    EXPECT_LT(sum / m.mesh.vertices.size(), 0.003) << method;
    EXPECT_LT(off, m.mesh.vertices.size() / 200) << method;
    EXPECT_EQ(m.surface_points > 0, method == "fused_bpa") << method;
  }
  // The fused map kept with the run (bpa_mesher_node: fused_map.vdb beside the mesh): both grids in an
  // OpenVDB file, and its surface points for the display; a path that cannot be written is said, and
  // the mesh stands.
  const FusedMesh saved = meshFusedMapDirectory(tmp.path + "/map", config, "marching_cubes", MesherConfig(), nullptr,
                                                tmp.path + "/fused_map.vdb");
  EXPECT_EQ(saved.save_problem, "");
  EXPECT_GT(saved.surface.size(), 10000u);
  {
    openvdb::initialize();
    openvdb::io::File file(tmp.path + "/fused_map.vdb");
    file.open();
    EXPECT_TRUE(file.hasGrid("tsdf"));
    EXPECT_TRUE(file.hasGrid("weight"));
    file.close();
  }
  const FusedMesh unsaved = meshFusedMapDirectory(tmp.path + "/map", config, "marching_cubes", MesherConfig(), nullptr,
                                                  tmp.path + "/no_such_dir/fused_map.vdb");
  EXPECT_NE(unsaved.save_problem.find(tmp.path + "/no_such_dir/fused_map.vdb"), std::string::npos)
      << unsaved.save_problem;
  EXPECT_GT(unsaved.mesh.faces.size(), 50000u);
  EXPECT_FALSE(isFusedMeshMethod("bpa"));
  EXPECT_THROW(meshFusedMapDirectory(tmp.path + "/map", config, "bpa", MesherConfig()), std::invalid_argument);
  EXPECT_THROW(meshFusedMapDirectory(tmp.path + "/missing", config, "marching_cubes", MesherConfig()), IoError);
}

TEST(FusedMap, TwoThreadsGiveTheFieldOfOne) {
  // integrateMapDirectory on two threads (a scan each into grids of its own, merged; the far pass's
  // free updates counted apart and added at the end): the same voxels with the same weights, the
  // distances within float rounding, the same mesh.
  test_util::TempDir tmp("fused_map_test");
  test::writeRoomMap(tmp.path + "/map");
  FusedMapConfig config;
  config.carve_m = 0.2;
  config.carve_far = true;
  config.threads = 1;
  FusedMap one(config);
  EXPECT_EQ(integrateMapDirectory(one, tmp.path + "/map"), 2u);
  config.threads = 2;
  FusedMap two(config);
  EXPECT_EQ(integrateMapDirectory(two, tmp.path + "/map"), 2u);
  EXPECT_EQ(two.stats().scans, 2u);
  EXPECT_EQ(one.stats().points, two.stats().points);
  EXPECT_EQ(one.stats().voxel_updates, two.stats().voxel_updates);
  EXPECT_EQ(one.activeVoxels(), two.activeVoxels());
  EXPECT_EQ(one.observedVoxels(), two.observedVoxels());
  const test::Box room = test::roomBounds();
  float worst = 0.0f;
  size_t samples = 0, other_weight = 0, seen = 0;
  for (float x = room.lo.x() - 0.1f; x <= room.hi.x() + 0.1f; x += 0.03f)
    for (float y = room.lo.y() - 0.1f; y <= room.hi.y() + 0.1f; y += 0.03f)
      for (float z = room.lo.z() - 0.1f; z <= room.hi.z() + 0.1f; z += 0.03f) {
        const Eigen::Vector3f p(x, y, z);
        ++samples;
        seen += one.weightAt(p) > 0.0f;
        other_weight += one.weightAt(p) != two.weightAt(p);
        worst = std::max(worst, std::abs(one.distanceAt(p) - two.distanceAt(p)));
      }
  EXPECT_GT(seen, samples / 20) << "the samples reach the room's voxels";
  EXPECT_EQ(other_weight, 0u);
  EXPECT_LT(worst, 1e-5f);
  const TriangleMesh a = one.extractMesh(), b = two.extractMesh();
  EXPECT_NEAR(static_cast<double>(a.faces.size()), static_cast<double>(b.faces.size()), 0.001 * a.faces.size());
  // A map of another voxel cannot be merged.
  FusedMapConfig coarse;
  coarse.voxel_m = 0.04;
  coarse.truncation_m = 0.12;
  FusedMap other(coarse);
  EXPECT_THROW(two.merge(other), ConfigError);
}

// Two copies of the room 20 m apart along x: a slab reads only the scans whose beams reach it, and the
// mesh is still the whole map's.
TEST(FusedMap, ASlabReadsOnlyTheScansThatReachIt) {
  test_util::TempDir tmp("fused_map_test");
  const std::string dir = tmp.path + "/map";
  test::writeRoomMap(dir);
  {
    MapDirectory map(dir);
    ASSERT_EQ(map.size(), 2u);
    for (uint32_t i = 0; i < 2; ++i) {
      MapScanInfo info = map.scans()[i];
      const PointCloud scan = map.loadScan(i);
      info.index = i + 2;
      info.map_pose.x += 20.0;
      info.odom_pose = info.map_pose;
      map.append(info, scan);
    }
  }
  FusedMapConfig config;
  config.carve_m = 0.2;
  config.carve_far = true;
  config.voxel_m = 0.02;
  config.truncation_m = 0.06;
  const FusedMesh whole = meshFusedMapDirectory(dir, config, "marching_cubes", MesherConfig());
  ASSERT_EQ(whole.slabs, 1u);
  EXPECT_EQ(whole.scans_read, 4u);
  config.max_grid_mb = 0.3 * whole.memory_bytes / 1048576.0;  // more than one slab per room
  const FusedMesh slabs = meshFusedMapInSlabs(dir, config, "marching_cubes", MesherConfig(), nullptr, 0.2);
  EXPECT_GE(slabs.slabs, 4u);
  EXPECT_EQ(slabs.scans, 4u);
  EXPECT_LE(slabs.scans_read, 2 * slabs.slabs);  // each slab: the two scans of its room (or none)
  std::vector<Eigen::Vector3f> a = whole.mesh.vertices, b = slabs.mesh.vertices;
  const auto less = [](const Eigen::Vector3f& p, const Eigen::Vector3f& q) {
    return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  };
  std::sort(a.begin(), a.end(), less);
  std::sort(b.begin(), b.end(), less);
  // The same mesh but for a few faces at a slab border (also so when every slab reads every scan: the
  // far pass's band leaves differ across a border; measured 2 of 1.18 M faces here).
  std::vector<Eigen::Vector3f> common;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(common), less);
  EXPECT_GE(common.size(), a.size() - a.size() / 10000);
  EXPECT_NEAR(static_cast<double>(slabs.mesh.faces.size()), static_cast<double>(whole.mesh.faces.size()),
              1e-4 * whole.mesh.faces.size());
  // Each slab decimated before the next: the slabs still meet (their cuts are boundary, which the
  // decimation keeps), so the result has about the boundary of the whole mesh decimated at once; an open
  // seam would add about a thousand boundary edges per slab border (a 2 cm cut through the room's walls,
  // floor and ceiling).
  DecimateConfig dc;
  dc.max_error_m = 0.002;
  const FusedMesh decimated = meshFusedMapInSlabs(dir, config, "marching_cubes", MesherConfig(), nullptr, 0.2, &dc);
  EXPECT_GE(decimated.decimated.faces_before, slabs.mesh.faces.size());  // before the pinched fans dropped
  EXPECT_LT(decimated.mesh.faces.size(), slabs.mesh.faces.size() / 2);
  TriangleMesh at_once = slabs.mesh;
  decimateMesh(at_once, dc);
  const MeshTopology t = analyzeTopology(decimated.mesh), t1 = analyzeTopology(at_once);
  EXPECT_NEAR(static_cast<double>(t.boundary_edges), static_cast<double>(t1.boundary_edges), 500.0);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  // More faces than at once: the cuts stay as they were (here 1.48 times, in slabs of 1-2 m).
  EXPECT_GT(decimated.mesh.faces.size(), at_once.faces.size());
  EXPECT_LT(decimated.mesh.faces.size(), 1.6 * at_once.faces.size());
  // integrateMapDirectory with a choice of scans: only those are read; none chosen reads nothing.
  config.max_grid_mb = 500.0;
  FusedMap none(config);
  const std::vector<uint8_t> nothing(4, 0), wrong(3, 1);
  EXPECT_EQ(integrateMapDirectory(none, dir, nullptr, &nothing), 0u);
  EXPECT_EQ(none.activeVoxels(), 0u);
  EXPECT_THROW(integrateMapDirectory(none, dir, nullptr, &wrong), std::invalid_argument);
}

TEST(FusedMap, AMapTooLargeForTheGridsIsMeshedInSlabsWithTheSameMesh) {
  // The grids bounded below what the room needs as a whole: built in slabs along x, whose meshes
  // meet exactly (the same vertices, welded at the borders) and make the whole map's mesh.
  test_util::TempDir tmp("fused_map_test");
  test::writeRoomMap(tmp.path + "/map");
  FusedMapConfig config;
  config.carve_m = 0.2;
  config.carve_far = true;  // as bpa_mesher_node fuses
  config.voxel_m = 0.01;    // a few MB of grids, so that a bound in whole MB splits them
  config.truncation_m = 0.03;
  const FusedMesh whole = meshFusedMapDirectory(tmp.path + "/map", config, "marching_cubes", MesherConfig());
  ASSERT_EQ(whole.slabs, 1u);
  config.max_grid_mb = 0.45 * whole.memory_bytes / 1048576.0;
  FusedMapConfig slab_config = config;
  slab_config.max_grid_mb = 0.25 * whole.memory_bytes / 1048576.0;  // one scan of the room needs slabs too
  const FusedMesh slabs = meshFusedMapDirectory(tmp.path + "/map", config, "marching_cubes", MesherConfig(), nullptr,
                                                tmp.path + "/fused_map.vdb", 0.2);
  EXPECT_GE(slabs.slabs, 3u);
  EXPECT_LE(slabs.memory_bytes, config.max_grid_mb * 1048576.0 * 1.3);  // leaf nodes plus the internal ones
  EXPECT_EQ(slabs.scans, 2u);
  EXPECT_EQ(slabs.mesh.faces.size(), whole.mesh.faces.size());
  EXPECT_EQ(slabs.mesh.vertices.size(), whole.mesh.vertices.size());
  const MeshTopology whole_topology = analyzeTopology(whole.mesh);
  const MeshTopology slab_topology = analyzeTopology(slabs.mesh);
  EXPECT_EQ(slab_topology.boundary_edges, whole_topology.boundary_edges);  // no seam left open
  EXPECT_EQ(slab_topology.nonmanifold_edges, 0u);
  EXPECT_EQ(slab_topology.nonmanifold_vertices, 0u);
  // Every vertex of the slabs' mesh is one of the whole's.
  std::vector<Eigen::Vector3f> a = whole.mesh.vertices, b = slabs.mesh.vertices;
  const auto less = [](const Eigen::Vector3f& p, const Eigen::Vector3f& q) {
    return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
  };
  std::sort(a.begin(), a.end(), less);
  std::sort(b.begin(), b.end(), less);
  EXPECT_TRUE(a == b);
  EXPECT_EQ(slabs.surface.size(), whole.surface.size());
  // A slab no narrower than min_slab_m that still does not fit: GridBoundError, naming the slab.
  config.max_grid_mb = 1.0;
  ASSERT_GT(whole.memory_bytes, 6 * 1048576u);
  try {
    meshFusedMapDirectory(tmp.path + "/map", config, "marching_cubes", MesherConfig(), nullptr, "", 1.0);
    ADD_FAILURE() << "no GridBoundError";
  } catch (const GridBoundError& e) {
    EXPECT_NE(std::string(e.what()).find("in a slab of"), std::string::npos) << e.what();
  }
  // A scan that cannot be read: skipped (with skipped given) and named once, however many passes.
  {
    std::ofstream bad(tmp.path + "/map/scans/scan_0001.pcd", std::ios::trunc);
    bad << "not a point cloud\n";
  }
  std::vector<std::string> skipped;
  const FusedMesh rest =
      meshFusedMapDirectory(tmp.path + "/map", slab_config, "marching_cubes", MesherConfig(), &skipped, "", 0.2);
  EXPECT_GE(rest.slabs, 2u);
  EXPECT_EQ(rest.scans, 1u);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_NE(skipped[0].find("scan 1 skipped"), std::string::npos) << skipped[0];
}
