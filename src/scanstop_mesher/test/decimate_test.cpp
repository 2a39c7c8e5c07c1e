// Quadric edge-collapse decimation (issue #20: the fused map's mesh within 1 M triangles): a flat
// patch shrinks to a handful of triangles and keeps its outline, a sphere stays closed, manifold and
// on the sphere, the face target and the error bound hold, bad input is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_mesher/decimate.h"
#include "scanstop_mesher/mesh_analysis.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

/// An n x n grid of squares (2 triangles each) over [0, size]^2 at z = 0 (plus noise of sigma [m]),
/// counter-clockwise seen from +z, with normals.
TriangleMesh gridPatch(int n, double size, double sigma = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma > 0 ? sigma : 1.0);
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(size * i / n, size * j / n, sigma > 0 ? noise(rng) : 0.0);
  const auto at = [n](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.faces.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      m.faces.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  m.normals.assign(m.vertices.size(), Eigen::Vector3f::UnitZ());
  return m;
}

/// An icosphere of radius r about the origin: the icosahedron subdivided `levels` times, faces
/// counter-clockwise seen from outside.
TriangleMesh icosphere(double r, int levels) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto middle = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& t3 : f) {
      const int a = middle(t3[0], t3[1]), b = middle(t3[1], t3[2]), c = middle(t3[2], t3[0]);
      g.emplace_back(t3[0], a, c);
      g.emplace_back(t3[1], b, a);
      g.emplace_back(t3[2], c, b);
      g.emplace_back(a, b, c);
    }
    f = g;
  }
  TriangleMesh m;
  for (const auto& p : v) {
    m.vertices.push_back((r * p).cast<float>());
    m.normals.push_back(p.cast<float>());
  }
  m.faces = f;
  return m;
}

/// The boundary edges of a mesh as pairs of vertex positions (order-free).
std::set<std::pair<std::vector<float>, std::vector<float>>> boundary(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) ++count[{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])}];
  std::set<std::pair<std::vector<float>, std::vector<float>>> out;
  for (const auto& [e, c] : count) {
    if (c != 1) continue;
    const Eigen::Vector3f a = m.vertices[e.first], b = m.vertices[e.second];
    std::vector<float> pa{a.x(), a.y(), a.z()}, pb{b.x(), b.y(), b.z()};
    out.insert(std::min(pa, pb) == pa ? std::make_pair(pa, pb) : std::make_pair(pb, pa));
  }
  return out;
}

TEST(Decimate, FlatPatchShrinksToAFewTrianglesAndKeepsItsOutline) {
  TriangleMesh m = gridPatch(60, 3.0);  // 7200 triangles, 240 boundary edges
  const auto outline = boundary(m);
  const DecimateStats s = decimateMesh(m, DecimateConfig());
  EXPECT_EQ(s.faces_before, 7200u);
  EXPECT_EQ(s.faces_after, m.faces.size());
  // The interior vertices all go; only the 240 boundary vertices remain (a fan-like
  // triangulation of the outline: 240 - 2 triangles at the least).
  EXPECT_LE(m.faces.size(), 400u);
  EXPECT_EQ(s.locked_vertices, 240u);
  EXPECT_EQ(boundary(m), outline);
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.degenerate_faces, 0u);
  for (const auto& v : m.vertices) EXPECT_EQ(v.z(), 0.0f);
  for (size_t i = 0; i < m.faces.size(); ++i) EXPECT_GT(m.faceNormal(i).z(), 0.99f) << "face " << i << " turned";
  ASSERT_EQ(m.normals.size(), m.vertices.size());
  for (const auto& n : m.normals) EXPECT_GT(n.z(), 0.99f);
}

// Vertices the caller pins stay, on one thread and in the two halves: a band across a flat patch (a
// slab's border band in meshFusedMapInSlabs) keeps all its vertices, the rest of the patch still goes.
TEST(Decimate, PinnedVerticesStay) {
  for (int n : {60, 240}) {  // 7,200 faces (one thread) and 115,200 (two halves)
    TriangleMesh m = gridPatch(n, 3.0);
    std::vector<char> pinned(m.vertices.size(), 0);
    std::vector<Eigen::Vector3f> band;
    for (size_t i = 0; i < m.vertices.size(); ++i)
      if (std::fabs(m.vertices[i].x() - 1.0f) < 0.01f) {  // the column at x = 1 m
        pinned[i] = 1;
        band.push_back(m.vertices[i]);
      }
    ASSERT_EQ(band.size(), static_cast<size_t>(n + 1));
    const size_t before = m.faces.size();
    decimateMesh(m, DecimateConfig(), pinned);
    EXPECT_LT(m.faces.size(), before / 10) << n;
    for (const Eigen::Vector3f& v : band)
      EXPECT_NE(std::find(m.vertices.begin(), m.vertices.end(), v), m.vertices.end()) << n << ": " << v.transpose();
    EXPECT_TRUE(analyzeTopology(m).manifold()) << n;
  }
}

TEST(Decimate, NoiseWithinTheBoundIsSmoothedAwayNoiseAboveItIsKept) {
  // 0.3 mm of noise on a flat patch: a 1 mm bound removes most of it; a 0.1 mm bound keeps most.
  TriangleMesh fine = gridPatch(40, 2.0, 0.0003), strict = fine;
  DecimateConfig mm;
  mm.max_error_m = 0.001;
  decimateMesh(fine, mm);
  EXPECT_LT(fine.faces.size(), 3200u / 5);
  DecimateConfig tight;
  tight.max_error_m = 0.0001;
  decimateMesh(strict, tight);
  EXPECT_GT(strict.faces.size(), 3200u / 2);
}

TEST(Decimate, SphereStaysClosedManifoldAndOnTheSphere) {
  const double r = 0.5;
  TriangleMesh m = icosphere(r, 5);  // 20480 triangles, edges about 2.3 cm
  DecimateConfig config;
  config.max_error_m = 0.001;
  const DecimateStats s = decimateMesh(m, config);
  EXPECT_LT(m.faces.size(), 20480u / 2) << "a 1 mm bound on a 0.5 m sphere leaves room for longer edges";
  EXPECT_GT(m.faces.size(), 500u);
  EXPECT_LE(s.max_error_m, 0.001 + 1e-9);
  const MeshTopology t = analyzeTopology(m);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.boundary_edges, 0u);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.components, 1u);
  // The vertices stay near the sphere, and so do the faces between them (sagitta of the longer edges).
  double worst_vertex = 0.0;
  for (const auto& v : m.vertices) worst_vertex = std::max(worst_vertex, std::abs(v.cast<double>().norm() - r));
  EXPECT_LT(worst_vertex, 0.003);
  double worst_face = 0.0;
  for (const auto& p : sampleFaces(m)) worst_face = std::max(worst_face, std::abs(p.cast<double>().norm() - r));
  EXPECT_LT(worst_face, 0.006);
  for (size_t i = 0; i < m.faces.size(); ++i) {
    const Eigen::Vector3f c =
        (m.vertices[m.faces[i][0]] + m.vertices[m.faces[i][1]] + m.vertices[m.faces[i][2]]) / 3.0f;
    EXPECT_GT(m.faceNormal(i).dot(c.normalized()), 0.5f) << "face " << i << " no longer faces outwards";
  }
}

TEST(Decimate, StopsAtTheFaceTargetAndIsDeterministic) {
  TriangleMesh a = icosphere(0.5, 4), b = a;
  DecimateConfig config;
  config.max_error_m = 0.1;
  config.max_faces = 1000;
  decimateMesh(a, config);
  decimateMesh(b, config);
  EXPECT_LE(a.faces.size(), 1000u);
  EXPECT_GE(a.faces.size(), 990u);  // each collapse removes two faces
  ASSERT_EQ(a.faces.size(), b.faces.size());
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_EQ(a.vertices, b.vertices);
}

TEST(Decimate, TwoHalvesOnTwoThreadsMeetExactly) {
  // A noisy 2.6 x 2.6 m patch of 135,200 faces (above kMinFacesToSplit): decimated in two halves,
  // the seam joined, the outline kept; as much as on one thread, within the seam's own vertices.
  TriangleMesh two = gridPatch(260, 2.6, 0.0002), one = two;
  ASSERT_GE(two.faces.size(), kMinFacesToSplit);
  const auto outline = boundary(two);
  DecimateConfig config;
  config.max_error_m = 0.001;
  const DecimateStats s = decimateMesh(two, config);
  config.threads = 1;
  const DecimateStats s1 = decimateMesh(one, config);
  EXPECT_EQ(s.faces_after, two.faces.size());
  EXPECT_EQ(s.vertices_after, two.vertices.size());
  EXPECT_LT(two.faces.size(), 135200u / 20);
  EXPECT_LT(two.faces.size(), one.faces.size() + 4 * 260u) << "the seam is one column of vertices";
  EXPECT_LE(s.max_error_m, 0.001 + 1e-9);
  EXPECT_EQ(boundary(two), outline) << "a seam that did not close would add boundary edges";
  EXPECT_EQ(boundary(one), outline);
  const MeshTopology t = analyzeTopology(two);
  EXPECT_TRUE(t.manifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.euler(), 1) << "still one disc";
  ASSERT_EQ(two.normals.size(), two.vertices.size());
  for (size_t i = 0; i < two.faces.size(); ++i) ASSERT_GT(two.faceNormal(i).z(), 0.9f) << "face " << i;
  EXPECT_GT(s1.collapses, 0u);
}

TEST(Decimate, ZeroBoundAndEmptyMeshChangeNothing) {
  TriangleMesh m = gridPatch(10, 1.0), copy = m;
  DecimateConfig none;
  none.max_error_m = 0.0;
  const DecimateStats s = decimateMesh(m, none);
  EXPECT_EQ(s.collapses, 0u);
  EXPECT_EQ(m.faces, copy.faces);
  EXPECT_EQ(m.vertices, copy.vertices);
  TriangleMesh empty;
  EXPECT_EQ(decimateMesh(empty, DecimateConfig()).faces_after, 0u);
}

TEST(Decimate, BadInputIsRefusedByName) {
  TriangleMesh m = gridPatch(4, 1.0);
  DecimateConfig bad;
  bad.max_error_m = 0.5;
  try {
    decimateMesh(m, bad);
    FAIL() << "a 0.5 m bound was taken";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("max_error_m"), std::string::npos) << e.what();
  }
  m.faces.emplace_back(0, 1, 999);
  try {
    decimateMesh(m, DecimateConfig());
    FAIL() << "a face with vertex 999 of 25 was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("999"), std::string::npos) << e.what();
  }
}

TEST(Decimate, RepeatedIndicesAndNonManifoldEdgesDoNotBreakIt) {
  TriangleMesh m = gridPatch(10, 1.0);
  const size_t n = m.vertices.size();
  m.faces.emplace_back(3, 3, 4);  // a degenerate face: dropped
  // A fin on an interior edge (a third face on it): that edge's vertices stay.
  m.vertices.emplace_back(0.5f, 0.5f, 0.3f);
  const Eigen::Vector3i e = m.faces[100];
  m.faces.emplace_back(e[0], e[1], static_cast<int>(n));
  m.normals.push_back(Eigen::Vector3f::UnitZ());
  decimateMesh(m, DecimateConfig());
  for (const auto& f : m.faces) EXPECT_TRUE(f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
  const MeshTopology t = analyzeTopology(m);
  EXPECT_EQ(t.nonmanifold_edges, 1u) << "the fin stays where it was";
}

}  // namespace

TEST(DecimateStats, AddSumsThePartsAndKeepsTheLargestError) {
  DecimateStats a, b;
  a.faces_before = 10;
  a.faces_after = 4;
  a.vertices_before = 8;
  a.vertices_after = 5;
  a.collapses = 3;
  a.refused = 1;
  a.locked_vertices = 2;
  a.max_error_m = 0.002;
  a.seconds = 1.5;
  b = a;
  b.max_error_m = 0.001;
  a.add(b);
  EXPECT_EQ(a.faces_before, 20u);
  EXPECT_EQ(a.faces_after, 8u);
  EXPECT_EQ(a.vertices_before, 16u);
  EXPECT_EQ(a.vertices_after, 10u);
  EXPECT_EQ(a.collapses, 6u);
  EXPECT_EQ(a.refused, 2u);
  EXPECT_EQ(a.locked_vertices, 4u);
  EXPECT_DOUBLE_EQ(a.max_error_m, 0.002);
  EXPECT_DOUBLE_EQ(a.seconds, 3.0);
}
