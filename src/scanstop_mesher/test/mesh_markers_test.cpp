// Mesh -> rviz markers, without a roscore.
#include <gtest/gtest.h>

#include "scanstop_common/error.h"
#include "scanstop_mesher/mesh_markers.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {
TriangleMesh strip(int n) {
  TriangleMesh m;
  for (int i = 0; i <= n + 1; ++i) {
    m.vertices.emplace_back(0.1f * i, (i % 2) * 0.1f, 0.05f * i);
    m.normals.emplace_back(0, 0, 1);
  }
  for (int i = 0; i < n; ++i) m.faces.emplace_back(i, i + 1, i + 2);
  return m;
}
}  // namespace

TEST(MeshMarkers, SplitsLargeMeshesAndClearsFirst) {
  const TriangleMesh m = strip(25);
  const auto arr = meshToMarkers(m, "map", ros::Time(5.0), MeshColoring::kHeight, 10);
  ASSERT_EQ(arr.markers.size(), 4u);  // DELETEALL + 10 + 10 + 5
  EXPECT_EQ(arr.markers[0].action, visualization_msgs::Marker::DELETEALL);
  size_t triangles = 0;
  for (size_t k = 1; k < arr.markers.size(); ++k) {
    const auto& mk = arr.markers[k];
    EXPECT_EQ(mk.type, visualization_msgs::Marker::TRIANGLE_LIST);
    EXPECT_EQ(mk.header.frame_id, "map");
    EXPECT_EQ(mk.id, static_cast<int>(k - 1));
    EXPECT_EQ(mk.points.size() % 3, 0u);
    EXPECT_EQ(mk.colors.size(), mk.points.size());
    triangles += mk.points.size() / 3;
  }
  EXPECT_EQ(triangles, 25u);
  // First corner of the last triangle = vertex 24.
  EXPECT_FLOAT_EQ(arr.markers[3].points[12].x, 2.4f);
  // Height colouring: low vertices blue, high ones red.
  EXPECT_GT(arr.markers[1].colors[0].b, 0.9f);
  EXPECT_GT(arr.markers[3].colors.back().r, 0.9f);
}

TEST(MeshMarkers, LargeMeshesShowEveryKthTriangle) {
  const TriangleMesh m = strip(25);
  const auto arr = meshToMarkers(m, "map", ros::Time(1.0), MeshColoring::kHeight, 4, 10);  // k = 3
  size_t triangles = 0;
  for (size_t k = 1; k < arr.markers.size(); ++k) triangles += arr.markers[k].points.size() / 3;
  EXPECT_EQ(triangles, 9u);                           // faces 0, 3, ..., 24
  EXPECT_EQ(arr.markers.size(), 4u);                  // DELETEALL + 4 + 4 + 1
  EXPECT_FLOAT_EQ(arr.markers[1].points[3].x, 0.3f);  // first corner of face 3 = vertex 3
}

TEST(MeshMarkers, NormalColouringAndBadMode) {
  const auto arr = meshToMarkers(strip(3), "map", ros::Time(1.0), MeshColoring::kNormal, 100);
  ASSERT_EQ(arr.markers.size(), 2u);
  EXPECT_FLOAT_EQ(arr.markers[1].colors[0].b, 1.0f);
  EXPECT_FLOAT_EQ(arr.markers[1].colors[0].r, 0.0f);
  EXPECT_EQ(meshToMarkers(TriangleMesh(), "map", ros::Time(1.0), MeshColoring::kNormal, 100).markers.size(), 1u);
  EXPECT_THROW(parseColoring("rainbow", "color_mode"), ConfigError);
  EXPECT_EQ(parseColoring("normal", "color_mode"), MeshColoring::kNormal);
}

// #21 point 3 / #20: view_run.launch opened rviz on a closed box (the ceiling hid the room). Triangles
// reaching above max_z are not shown; the height colours span what is shown.
TEST(MeshMarkers, TrianglesAboveTheDisplayHeightAreLeftOut) {
  const TriangleMesh m = strip(25);  // vertex i at z = 0.05 i
  const auto arr = meshToMarkers(m, "map", ros::Time(1.0), MeshColoring::kHeight, 100, 0, 0.5f);
  ASSERT_EQ(arr.markers.size(), 2u);
  EXPECT_EQ(arr.markers[1].points.size(), 3u * 9u);  // faces 0..8 (vertices 0..10, z <= 0.5)
  for (const auto& p : arr.markers[1].points) EXPECT_LE(p.z, 0.5 + 1e-6);
  EXPECT_GT(arr.markers[1].colors.back().r, 0.9f);  // the highest shown vertex is red
  // Everything above: only the DELETEALL.
  EXPECT_EQ(meshToMarkers(m, "map", ros::Time(1.0), MeshColoring::kHeight, 100, 0, -1.0f).markers.size(), 1u);
}
