// bpa_mesher_node wiring: mesher/build_mesh on the current map directory and on files, errors
// reported in the response, the mesh as markers; the viewing instance's saved mesh and map view.
#include <geometry_msgs/PoseArray.h>
#include <gtest/gtest.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <scanstop_msgs/BuildMesh.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <functional>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "synthetic_room.h"

using namespace scanstop;

namespace {

std::string g_map_dir, g_reference;

size_t triangles(const visualization_msgs::MarkerArray& arr) {
  size_t n = 0;
  for (const auto& m : arr.markers)
    if (m.type == visualization_msgs::Marker::TRIANGLE_LIST) n += m.points.size() / 3;
  return n;
}

bool spinUntil(const std::function<bool()>& done, double timeout_s) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return done();
}

/// Two scans of the synthetic room from two poses, written as a map directory.
void writeMap(const std::string& dir) {
  MapDirectory map(dir);
  const Pose2D poses[2] = {Pose2D(-1.0, 0.5, 0.3), Pose2D(0.5, -1.0, -2.0)};
  for (uint32_t s = 0; s < 2; ++s) {
    MapScanInfo info;
    info.index = s;
    info.map_pose = info.odom_pose = poses[s];
    info.sensor_origin = Eigen::Vector3d(0.1, 0.0, 0.45);
    const Eigen::Isometry3f T_map_base = poses[s].toIsometry3f();
    PointCloud base;
    for (const auto& p : test::scanRoom(T_map_base * info.sensor_origin.cast<float>(), 90, 180, 0.002f, s + 1))
      base.push_back(T_map_base.inverse() * p);
    map.append(info, base);
  }
}

}  // namespace

TEST(BpaMesherNode, BuildsMeshesOfTheMapAndOfFilesAndReportsErrors) {
  ros::NodeHandle nh;
  visualization_msgs::MarkerArray markers, viewer_markers;
  bool got = false, viewer_got = false;
  sensor_msgs::PointCloud2 map_cloud;
  nav_msgs::Path path;
  geometry_msgs::PoseArray scan_poses;
  auto s1 = nh.subscribe<visualization_msgs::MarkerArray>("mesher/mesh_markers", 1, [&](const auto& m) {
    markers = *m;
    got = true;
  });
  auto s2 = nh.subscribe<visualization_msgs::MarkerArray>("viewer/mesher/mesh_markers", 1, [&](const auto& m) {
    viewer_markers = *m;
    viewer_got = true;
  });
  auto s3 = nh.subscribe<sensor_msgs::PointCloud2>("viewer/slam/map_cloud", 1, [&](const auto& m) { map_cloud = *m; });
  auto s4 = nh.subscribe<nav_msgs::Path>("viewer/slam/path", 1, [&](const auto& m) { path = *m; });
  auto s5 =
      nh.subscribe<geometry_msgs::PoseArray>("viewer/mesher/scan_poses", 1, [&](const auto& m) { scan_poses = *m; });

  // The viewer shows the saved mesh right away.
  ASSERT_TRUE(spinUntil([&] { return viewer_got; }, 20.0));
  EXPECT_EQ(triangles(viewer_markers), readMesh(g_reference).faces.size());

  ASSERT_TRUE(ros::service::waitForService("mesher/build_mesh", 30000));
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::BuildMesh>("mesher/build_mesh");
  scanstop_msgs::BuildMesh srv;
  srv.request.output_path = g_map_dir + "/mesh.ply";
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success) << "no directory for the output yet";
  EXPECT_NE(srv.response.message.find("does not exist"), std::string::npos) << srv.response.message;
  ASSERT_EQ(::mkdir(g_map_dir.c_str(), 0755), 0);  // the run directory exists, the map not yet
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success) << "no map yet";
  EXPECT_NE(srv.response.message.find("poses.csv"), std::string::npos) << srv.response.message;

  writeMap(g_map_dir);
  // The viewer notices the new scans: map points, path and scan poses.
  EXPECT_TRUE(spinUntil([&] { return map_cloud.width * map_cloud.height > 1000 && path.poses.size() == 2; }, 10.0));
  EXPECT_EQ(map_cloud.header.frame_id, "map");
  EXPECT_EQ(scan_poses.poses.size(), 2u);

  // The current map (empty input_path), automatic radii, the node's map voxel.
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_GT(srv.response.triangles, 2000u);
  EXPECT_GT(srv.response.points, 1000u);
  EXPECT_GT(srv.response.duration_s, 0.0);
  EXPECT_EQ(srv.response.file, g_map_dir + "/mesh.ply");
  const TriangleMesh ply = readMesh(srv.response.file);
  EXPECT_EQ(ply.faces.size(), srv.response.triangles);
  EXPECT_EQ(ply.normals.size(), ply.vertices.size());
  // Shown: the triangles below display_max_z_m (2 m; the room's ceiling at 2.5 m would hide it in rviz).
  size_t below = 0;
  for (const auto& f : ply.faces)
    below += ply.vertices[f[0]].z() <= 2.0f && ply.vertices[f[1]].z() <= 2.0f && ply.vertices[f[2]].z() <= 2.0f;
  EXPECT_LT(below, ply.faces.size()) << "the ceiling is not cut away from the view";
  EXPECT_GT(below, ply.faces.size() / 2);
  ASSERT_TRUE(spinUntil([&] { return got && triangles(markers) == below; }, 10.0));
  EXPECT_GT(markers.markers.size(), 2u) << "split into markers of at most 5000 triangles";
  for (const auto& m : markers.markers)
    if (m.type == visualization_msgs::Marker::TRIANGLE_LIST) {
      EXPECT_LE(m.points.size(), 15000u);
      EXPECT_EQ(m.header.frame_id, "map");
    }
  // The markers are not latched (the node keeps no mesh in memory): a subscriber that comes later
  // (rviz opened after the mesh) gets the same mesh read back from its file.
  // (This process must drop its subscription first: roscpp shares one connection per topic.)
  s1.shutdown();
  ros::WallDuration(0.5).sleep();
  visualization_msgs::MarkerArray late_markers;
  auto late = nh.subscribe<visualization_msgs::MarkerArray>("mesher/mesh_markers", 1,
                                                            [&](const auto& m) { late_markers = *m; });
  EXPECT_TRUE(spinUntil([&] { return triangles(late_markers) == below; }, 10.0))
      << triangles(late_markers) << " triangles for a late subscriber";

  // A file as input, given radii, binary STL out.
  const std::string cloud = g_map_dir + "/scans/scan_0000.pcd";
  srv.request.input_path = cloud;
  srv.request.output_path = g_map_dir + "/scan0.stl";
  srv.request.radii = {0.08, 0.16};
  srv.request.voxel_m = 0.06;
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(readMesh(g_map_dir + "/scan0.stl").faces.size(), srv.response.triangles);

  // Errors come back in the response, naming what was wrong.
  srv.request.input_path = g_map_dir + "/missing.ply";
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("missing.ply"), std::string::npos) << srv.response.message;
  srv.request.input_path = cloud;
  srv.request.radii = {0.2, 0.1};
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("increase"), std::string::npos) << srv.response.message;
  srv.request.radii = {};
  srv.request.output_path = g_map_dir + "/mesh.obj";
  ASSERT_TRUE(client.call(srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find(".obj"), std::string::npos) << srv.response.message;
}

// A fused mesh_method: the mesh, the fused map kept beside it (fused_map.vdb) and its surface points on
// mesher/fused_cloud, without the ceiling (display_max_z_m). The first test writes the map; written
// here when that one stopped before it.
TEST(BpaMesherNode, AFusedMethodKeepsTheFusedMapWithTheRunAndShowsItsSurface) {
  ros::NodeHandle nh;
  struct stat map_st;
  if (::stat((g_map_dir + "/poses.csv").c_str(), &map_st) != 0) {
    ::mkdir(g_map_dir.c_str(), 0755);
    writeMap(g_map_dir);
  }
  sensor_msgs::PointCloud2 fused;
  auto sub = nh.subscribe<sensor_msgs::PointCloud2>("fused/mesher/fused_cloud", 1, [&](const auto& m) { fused = *m; });
  ASSERT_TRUE(ros::service::waitForService("fused/mesher/build_mesh", 30000));
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::BuildMesh>("fused/mesher/build_mesh");
  scanstop_msgs::BuildMesh srv;
  srv.request.output_path = g_map_dir + "/fused_mesh.ply";
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_GT(srv.response.triangles, 200u);
  EXPECT_NE(srv.response.message.find("fused map in " + g_map_dir + "/fused_map.vdb"), std::string::npos)
      << srv.response.message;
  // The Marching Cubes mesh decimated within mesh_decimate_error_m (2 mm): the synthetic room's flat
  // walls and box keep under half of their triangles (3,118 of 10,378 measured at the 0.04 m voxel).
  const size_t at = srv.response.message.find("decimated from ");
  ASSERT_NE(at, std::string::npos) << srv.response.message;
  const unsigned long before = std::stoul(srv.response.message.substr(at + 15));
  EXPECT_NE(srv.response.message.find(" within 2 mm in "), std::string::npos) << srv.response.message;
  EXPECT_LT(srv.response.triangles * 2ul, before) << srv.response.message;
  EXPECT_EQ(readMesh(g_map_dir + "/fused_mesh.ply").faces.size(), srv.response.triangles);
  // The fused map was kept up to date while the map grew (fused_incremental): build_mesh found it
  // ready.
  EXPECT_NE(srv.response.message.find("kept during the mission"), std::string::npos) << srv.response.message;
  // SLAM moves a scan by 5 cm (a relaxation): the next build integrates it again there.
  {
    MapDirectory map(g_map_dir);
    Pose2D pose = map.scans()[1].map_pose;
    pose.x += 0.05;
    map.updatePoses({{map.scans()[1].index, pose}});
  }
  srv.request.output_path = g_map_dir + "/fused_mesh_moved.ply";
  ASSERT_TRUE(client.call(srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_NE(srv.response.message.find("(0 new, 1 moved scans)"), std::string::npos) << srv.response.message;
  struct stat st;
  ASSERT_EQ(::stat((g_map_dir + "/fused_map.vdb").c_str(), &st), 0) << "no fused_map.vdb beside the mesh";
  EXPECT_GT(st.st_size, 10000);
  ASSERT_TRUE(spinUntil([&] { return fused.width * fused.height > 1000; }, 10.0)) << "no fused surface shown";
  EXPECT_EQ(fused.header.frame_id, "map");
  PointCloud cloud = ros_conv::fromMsg(fused);
  float top = -1e9f;
  for (const auto& p : cloud.points) top = std::max(top, p.z());
  EXPECT_LE(top, 2.0f) << "the ceiling (2.5 m) is not cut away from the view";
  EXPECT_GT(top, 1.0f);
}

// A map whose fused grids would pass fused_max_grid_mb as a whole is built in slabs along x at the
// same voxel; one whose 1 m slabs do not fit either at a coarser voxel (up to 4 times); one that fits
// at none is meshed by Ball Pivoting of its points. Each response says which.
TEST(BpaMesherNode, AMapTooLargeForTheFusedGridsIsBuiltInSlabsOrCoarserOrMeshedByBallPivoting) {
  ros::NodeHandle nh;
  struct stat map_st;
  if (::stat((g_map_dir + "/poses.csv").c_str(), &map_st) != 0) {
    ::mkdir(g_map_dir.c_str(), 0755);
    writeMap(g_map_dir);
  }
  const auto build = [&](const std::string& ns) {
    EXPECT_TRUE(ros::service::waitForService(ns + "/mesher/build_mesh", 30000)) << ns;
    ros::ServiceClient client = nh.serviceClient<scanstop_msgs::BuildMesh>(ns + "/mesher/build_mesh");
    scanstop_msgs::BuildMesh srv;
    srv.request.output_path = g_map_dir + "/" + ns + "_mesh.ply";
    EXPECT_TRUE(client.call(srv)) << ns;
    EXPECT_TRUE(srv.response.success) << ns << ": " << srv.response.message;
    struct stat st;
    EXPECT_EQ(::stat((g_map_dir + "/" + ns + "_mesh.ply").c_str(), &st), 0) << ns << ": no mesh";
    EXPECT_NE(::stat((g_map_dir + "/" + ns + ".vdb").c_str(), &st), 0)
        << ns << ": a .vdb of a fused map not built whole";
    return srv.response;
  };
  const scanstop_msgs::BuildMesh::Response slabs = build("slabs");
  EXPECT_GT(slabs.triangles, 500u);
  EXPECT_NE(slabs.message.find("by marching_cubes of the fused map"), std::string::npos) << slabs.message;
  EXPECT_NE(slabs.message.find("(voxel 0.02 m"), std::string::npos) << slabs.message;
  EXPECT_NE(slabs.message.find(" slabs along x, the largest within fused_max_grid_mb"), std::string::npos)
      << slabs.message;
  const scanstop_msgs::BuildMesh::Response coarser = build("coarser");
  EXPECT_GT(coarser.triangles, 1000u);
  EXPECT_NE(
      coarser.message.find("m voxel: at 0.02 m (fused_voxel_m) the grids needed more than fused_max_grid_mb = 2 MB"),
      std::string::npos)
      << coarser.message;
  const scanstop_msgs::BuildMesh::Response bounded = build("bounded");
  EXPECT_GT(bounded.triangles, 2000u);
  EXPECT_NE(bounded.message.find("fused_max_grid_mb = 1 MB even at 4 times fused_voxel_m: meshed by Ball Pivoting"),
            std::string::npos)
      << bounded.message;
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "bpa_mesher_rostest");
  ros::NodeHandle pnh("~");
  pnh.getParam("map_dir", g_map_dir);
  pnh.getParam("reference_mesh", g_reference);
  const int rc = RUN_ALL_TESTS();
  if (!g_map_dir.empty() && g_map_dir.rfind("/tmp/", 0) == 0)
    if (std::system(("rm -rf '" + g_map_dir + "'").c_str()) != 0) std::perror("rm");
  return rc;
}
