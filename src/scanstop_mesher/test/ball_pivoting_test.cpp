// Ball Pivoting core on synthetic surfaces with known topology, and on the Stanford bunny.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/shared_data.h"
#include "scanstop_mesher/ball_pivoting.h"
#include "scanstop_mesher/mesh_analysis.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

struct Samples {
  std::vector<Eigen::Vector3f> points, normals;
  void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
    points.push_back(p);
    normals.push_back(n.normalized());
  }
};

/// Points on a sphere (Fibonacci spiral), normals outward.
Samples sphere(int n, float radius) {
  Samples s;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(1.0 - z * z);
    const Eigen::Vector3f d(static_cast<float>(r * std::cos(golden * i)), static_cast<float>(r * std::sin(golden * i)),
                            static_cast<float>(z));
    s.add(radius * d, d);
  }
  return s;
}

/// Jittered grid points on the six faces of an axis-aligned cube [0, size]^3, face normals outward.
Samples cube(float size, int per_side, unsigned seed) {
  Samples s;
  std::mt19937 rng(seed);
  const float step = size / per_side;
  std::uniform_real_distribution<float> jitter(-0.15f * step, 0.15f * step);
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = side ? 1.0f : -1.0f;
      for (int u = 0; u < per_side; ++u)
        for (int v = 0; v < per_side; ++v) {
          Eigen::Vector3f p;
          p[axis] = side ? size : 0.0f;
          p[(axis + 1) % 3] = (u + 0.5f) * step + jitter(rng);
          p[(axis + 2) % 3] = (v + 0.5f) * step + jitter(rng);
          s.add(p, n);
        }
    }
  return s;
}

/// Jittered grid on the square [0, size]^2 at height z with normal (0, 0, nz), without the points
/// within hole_radius of the centre.
Samples plane(float size, int per_side, float z, float nz, float hole_radius, unsigned seed) {
  Samples s;
  std::mt19937 rng(seed);
  const float step = size / per_side;
  std::uniform_real_distribution<float> jitter(-0.2f * step, 0.2f * step);
  for (int u = 0; u <= per_side; ++u)
    for (int v = 0; v <= per_side; ++v) {
      const Eigen::Vector3f p(u * step + jitter(rng), v * step + jitter(rng), z);
      if ((p.head<2>() - Eigen::Vector2f(size / 2, size / 2)).norm() < hole_radius) continue;
      s.add(p, Eigen::Vector3f(0, 0, nz));
    }
  return s;
}

/// Faces whose normal disagrees with the mean normal of their corners.
size_t misorientedFaces(const TriangleMesh& m) {
  size_t bad = 0;
  for (size_t i = 0; i < m.faces.size(); ++i) {
    const auto& f = m.faces[i];
    const Eigen::Vector3f n = m.normals[f[0]] + m.normals[f[1]] + m.normals[f[2]];
    if (m.faceNormal(i).dot(n) <= 0) ++bad;
  }
  return bad;
}

/// Signed volume enclosed by a closed mesh (positive when the faces face outwards).
double signedVolume(const TriangleMesh& m) {
  double v = 0;
  for (const auto& f : m.faces)
    v += m.vertices[f[0]].cast<double>().dot(m.vertices[f[1]].cast<double>().cross(m.vertices[f[2]].cast<double>())) /
         6.0;
  return v;
}

}  // namespace

TEST(BallPivoting, SphereIsClosedOrientedGenusZero) {
  const Samples s = sphere(3000, 1.0f);
  BallPivoting bpa(s.points, s.normals);
  bpa.pivot(0.08);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  EXPECT_EQ(t.vertices, 3000u);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.faces, 2u * 3000u - 4u);
  EXPECT_EQ(misorientedFaces(m), 0u);
  // Outward: the enclosed volume is positive and close to the sphere's.
  EXPECT_NEAR(signedVolume(m), 4.0 / 3.0 * M_PI, 0.05);
  // Closing the sphere needs every glue case but the loop merge on a single seed's front.
  EXPECT_GT(bpa.stats().glue[0] + bpa.stats().glue[1], 0u);
}

TEST(BallPivoting, FlippedNormalsGiveInwardFaces) {
  Samples s = sphere(1500, 1.0f);
  for (auto& n : s.normals) n = -n;
  const TriangleMesh m = ballPivot(s.points, s.normals, {0.11});
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.euler(), 2);
  EXPECT_LT(signedVolume(m), -4.0);
}

TEST(BallPivoting, CubeIsClosedWithTwoRadii) {
  const Samples s = cube(1.0f, 20, 3);
  BallPivoting bpa(s.points, s.normals);
  bpa.pivot(0.045);
  bpa.pivot(0.09);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold()) << t.nonmanifold_edges << " " << t.nonmanifold_vertices << " " << t.inconsistent_edges;
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.vertices, s.points.size());
  EXPECT_EQ(misorientedFaces(m), 0u);
  EXPECT_NEAR(signedVolume(m), 1.0, 0.08);
  ASSERT_EQ(bpa.stats().triangles_per_radius.size(), 2u);
}

TEST(BallPivoting, PlaneWithHoleKeepsTheHole) {
  const float hole = 0.2f;
  const Samples s = plane(1.0f, 40, 0.0f, 1.0f, hole, 5);
  BallPivoting bpa(s.points, s.normals);
  bpa.pivot(0.03);
  bpa.pivot(0.045);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.boundary_loops, 2u);  // the outer border and the hole
  EXPECT_EQ(t.euler(), 0);          // an annulus
  EXPECT_EQ(t.vertices, s.points.size());
  for (size_t i = 0; i < m.faces.size(); ++i) {
    EXPECT_GT(m.faceNormal(i).z(), 0.99f);
    const auto& f = m.faces[i];
    const Eigen::Vector3f c = (m.vertices[f[0]] + m.vertices[f[1]] + m.vertices[f[2]]) / 3.0f;
    EXPECT_GT((c.head<2>() - Eigen::Vector2f(0.5f, 0.5f)).norm(), hole - 0.05f) << "face " << i << " covers the hole";
  }
}

TEST(BallPivoting, TwoNearbyParallelPlanesStaySeparate) {
  // A thin plate: top at z = 0.03 facing up, bottom at z = 0 facing down; spacing 0.025.
  Samples s = plane(1.0f, 40, 0.0f, -1.0f, 0.0f, 7);
  const Samples top = plane(1.0f, 40, 0.03f, 1.0f, 0.0f, 8);
  s.points.insert(s.points.end(), top.points.begin(), top.points.end());
  s.normals.insert(s.normals.end(), top.normals.begin(), top.normals.end());
  BallPivoting bpa(s.points, s.normals);
  bpa.pivot(0.03);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.euler(), 2);  // two discs
  EXPECT_EQ(t.boundary_loops, 2u);
  size_t up = 0, down = 0;
  for (size_t i = 0; i < m.faces.size(); ++i) {
    const auto& f = m.faces[i];
    const float z0 = m.vertices[f[0]].z(), z1 = m.vertices[f[1]].z(), z2 = m.vertices[f[2]].z();
    ASSERT_TRUE(z0 == z1 && z1 == z2) << "face " << i << " bridges the planes";
    (m.faceNormal(i).z() > 0.99f ? up : down)++;
    if (z0 > 0.01f)
      EXPECT_GT(m.faceNormal(i).z(), 0.99f);
    else
      EXPECT_LT(m.faceNormal(i).z(), -0.99f);
  }
  EXPECT_GT(up, 2800u);
  EXPECT_GT(down, 2800u);
}

// Slabs meshed in parallel and stitched (run() with regions > 1): the same guarantees as one
// sequential surface, on every synthetic shape, with the seams closed.
TEST(BallPivoting, SlabsGiveTheSameClosedSphere) {
  const Samples s = sphere(3000, 1.0f);
  for (int regions : {2, 3, 5}) {
    BallPivoting bpa(s.points, s.normals);
    bpa.run({0.08}, regions);
    EXPECT_EQ(bpa.stats().regions, regions);
    EXPECT_EQ(bpa.checkFront(), "") << regions << " slabs";
    const TriangleMesh m = bpa.mesh();
    const MeshTopology t = analyzeTopology(m);
    EXPECT_EQ(t.vertices, 3000u) << regions << " slabs";
    EXPECT_TRUE(t.manifold()) << regions << " slabs";
    EXPECT_EQ(t.boundary_edges, 0u) << regions << " slabs";
    EXPECT_EQ(t.components, 1u) << regions << " slabs";
    EXPECT_EQ(t.euler(), 2) << regions << " slabs";
    EXPECT_EQ(misorientedFaces(m), 0u);
    EXPECT_NEAR(signedVolume(m), 4.0 / 3.0 * M_PI, 0.05);
    EXPECT_EQ(bpa.stats().triangles, m.faces.size());
  }
}

TEST(BallPivoting, SlabsCubeWithTwoRadiiAndPlaneWithHole) {
  const Samples c = cube(1.0f, 20, 3);
  BallPivoting bpa(c.points, c.normals);
  bpa.run({0.045, 0.09}, 3);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.vertices, c.points.size());
  EXPECT_NEAR(signedVolume(m), 1.0, 0.08);
  ASSERT_EQ(bpa.stats().triangles_per_radius.size(), 2u);
  EXPECT_LE(bpa.stats().triangles_per_radius[0], bpa.stats().triangles_per_radius[1]);
  EXPECT_EQ(bpa.stats().triangles_per_radius[1], bpa.stats().triangles);

  const float hole = 0.2f;
  const Samples s = plane(1.0f, 40, 0.0f, 1.0f, hole, 5);
  BallPivoting plate(s.points, s.normals);
  plate.run({0.03, 0.045}, 4);
  EXPECT_EQ(plate.checkFront(), "");
  const TriangleMesh pm = plate.mesh();
  const MeshTopology pt = analyzeTopology(pm);
  EXPECT_TRUE(pt.manifold());
  EXPECT_EQ(pt.components, 1u);
  EXPECT_EQ(pt.boundary_loops, 2u);
  EXPECT_EQ(pt.euler(), 0);
  EXPECT_EQ(pt.vertices, s.points.size());
  for (size_t i = 0; i < pm.faces.size(); ++i) {
    const auto& f = pm.faces[i];
    const Eigen::Vector3f ctr = (pm.vertices[f[0]] + pm.vertices[f[1]] + pm.vertices[f[2]]) / 3.0f;
    EXPECT_GT((ctr.head<2>() - Eigen::Vector2f(0.5f, 0.5f)).norm(), hole - 0.05f) << "face " << i << " covers the hole";
  }
}

TEST(BallPivoting, SlabsAreDeterministicAndRunChecksItsArguments) {
  const Samples s = sphere(2000, 1.0f);
  BallPivoting a(s.points, s.normals), b(s.points, s.normals);
  a.run({0.1}, 4);
  b.run({0.1}, 4);
  EXPECT_EQ(a.faces(), b.faces());
  BallPivoting c(s.points, s.normals);
  EXPECT_THROW(c.run({0.1}, -1), std::invalid_argument);
  EXPECT_THROW(c.run({0.1, 0.05}, 2), std::invalid_argument);
  EXPECT_THROW(c.run({std::nan("")}, 2), std::invalid_argument);
  EXPECT_TRUE(c.faces().empty());
  EXPECT_EQ(BallPivoting::automaticRegions(100000), 1);
  EXPECT_EQ(BallPivoting::automaticRegions(1000000), 2);
  EXPECT_EQ(BallPivoting::automaticRegions(4000000), 4);
  EXPECT_EQ(BallPivoting::automaticRegions(40000000), 4);
}

TEST(BallPivoting, PointsWithoutNormalAreSkipped) {
  Samples s = plane(1.0f, 20, 0.0f, 1.0f, 0.0f, 9);
  s.normals[10] = Eigen::Vector3f::Constant(std::nanf(""));
  s.normals[20] = Eigen::Vector3f::Zero();
  BallPivoting bpa(s.points, s.normals);
  bpa.pivot(0.06);
  EXPECT_EQ(bpa.stats().points, s.points.size() - 2);
  for (const auto& f : bpa.faces())
    for (int k = 0; k < 3; ++k) {
      EXPECT_NE(f[k], 10);
      EXPECT_NE(f[k], 20);
    }
}

TEST(BallPivoting, RejectsBadRadii) {
  const Samples s = sphere(100, 1.0f);
  BallPivoting bpa(s.points, s.normals);
  EXPECT_THROW(bpa.pivot(0.0), std::invalid_argument);
  EXPECT_THROW(bpa.pivot(std::nan("")), std::invalid_argument);
  bpa.pivot(0.5);
  EXPECT_THROW(bpa.pivot(0.4), std::invalid_argument);
  EXPECT_THROW(BallPivoting(s.points, {}), std::invalid_argument);
}

TEST(BallPivoting, TooSmallBallMakesNothing) {
  const Samples s = sphere(500, 1.0f);
  const TriangleMesh m = ballPivot(s.points, s.normals, {0.01});
  EXPECT_EQ(m.faces.size(), 0u);
}

TEST(MeshAnalysis, DetectsNonManifoldEdgeAndVertex) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {-1, 0, 0}, {-1, -1, 0}};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};  // edge 0-1 has three faces, two in the same direction
  MeshTopology t = analyzeTopology(m);
  EXPECT_EQ(t.nonmanifold_edges, 1u);
  m.faces = {{0, 1, 2}, {0, 5, 6}};  // two triangles touching at vertex 0 only
  t = analyzeTopology(m);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 1u);
  m.faces = {{0, 1, 2}, {0, 1, 3}};  // same direction on the shared edge
  t = analyzeTopology(m);
  EXPECT_EQ(t.inconsistent_edges, 1u);
}

TEST(MeshAnalysis, DistanceToSurface) {
  TriangleMesh ref;
  ref.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  ref.faces = {{0, 1, 2}};
  const SurfaceDistance d = distanceToSurface({{0.2f, 0.2f, 0.5f}, {2.0f, 0.0f, 0.0f}}, ref);
  EXPECT_NEAR(d.max_m, 1.0, 1e-6);
  EXPECT_NEAR(d.mean_m, 0.75, 1e-6);
}

// The Stanford bunny's reference vertices with normals from its faces: at least 95 % of the
// reference's 69,451 triangles, no non-manifold edge or vertex, within 0.1 mm of the surface.
TEST(BallPivoting, StanfordBunny) {
  const TriangleMesh ref = readPly(sharedDataPath("bunny/bun_zipper.ply"));
  ASSERT_EQ(ref.faces.size(), 69451u);
  const std::vector<Eigen::Vector3f> normals = vertexNormalsFromFaces(ref);
  const auto t0 = std::chrono::steady_clock::now();
  BallPivoting bpa(ref.vertices, normals);
  for (double r : {0.0012, 0.0024, 0.0048}) bpa.pivot(r);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  std::cout << "bunny: " << m.faces.size() << " triangles in " << s << " s, per radius";
  for (size_t n : bpa.stats().triangles_per_radius) std::cout << " " << n;
  std::cout << "; glue " << bpa.stats().glue[0] << " " << bpa.stats().glue[1] << " " << bpa.stats().glue[2] << " "
            << bpa.stats().glue[3] << ", refused " << bpa.stats().refused_interior << "+" << bpa.stats().refused_edge
            << ", pinches " << bpa.stats().pinches << ", dropped " << bpa.stats().dropped_triangles << ", seeds "
            << bpa.stats().seeds << std::endl;
  EXPECT_EQ(bpa.checkFront(), "");
  EXPECT_GE(m.faces.size(), static_cast<size_t>(std::ceil(0.95 * 69451)));
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(misorientedFaces(m), 0u);
  const SurfaceDistance d = distanceToSurface(sampleFaces(m), ref);
  std::cout << "bunny: mean distance " << d.mean_m * 1e3 << " mm, max " << d.max_m * 1e3 << " mm" << std::endl;
  EXPECT_LT(d.mean_m, 1e-4);
  // All four glue cases occur on real data.
  for (int c = 0; c < 4; ++c) EXPECT_GT(bpa.stats().glue[c], 0u) << "glue case " << c + 1;
}

// The bunny cut into four slabs meshed in parallel and stitched: the same quality targets.
TEST(BallPivoting, StanfordBunnyInSlabs) {
  const TriangleMesh ref = readPly(sharedDataPath("bunny/bun_zipper.ply"));
  const std::vector<Eigen::Vector3f> normals = vertexNormalsFromFaces(ref);
  BallPivoting bpa(ref.vertices, normals);
  bpa.run({0.0012, 0.0024, 0.0048}, 4);
  EXPECT_EQ(bpa.stats().regions, 4);
  EXPECT_EQ(bpa.checkFront(), "");
  const TriangleMesh m = bpa.mesh();
  const MeshTopology t = analyzeTopology(m);
  std::cout << "bunny in 4 slabs: " << m.faces.size() << " triangles (slabs " << bpa.stats().region_seconds
            << " s, seams " << bpa.stats().seam_seconds << " s)" << std::endl;
  EXPECT_GE(m.faces.size(), static_cast<size_t>(std::ceil(0.95 * 69451)));
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(misorientedFaces(m), 0u);
  EXPECT_LT(distanceToSurface(sampleFaces(m), ref).mean_m, 1e-4);
}
