#pragma once
/// bpa_mesher_node wires the meshing pipeline to ROS: the mesher/build_mesh service (a file or the
/// current map directory), the mesh as rviz markers, and, for viewing a recorded run, a saved mesh
/// and the map directory's points, path and scan poses.

#include <geometry_msgs/PoseArray.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <scanstop_msgs/BuildMesh.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "scanstop_mesher/fused_tracker.h"
#include "scanstop_mesher/mesh_markers.h"
#include "scanstop_mesher/mesher.h"

namespace scanstop {
namespace mesher {

/// Node parameters (private namespace); see the README section "bpa_mesher_node" for the table.
struct MesherNodeConfig {
  std::string map_dir;           ///< map directory meshed when input_path is empty
  std::string frame_id = "map";  ///< frame of the map, the meshes and the markers
  std::string default_output;    ///< file written when output_path is empty ("" = required)
  /// The only directory meshes may be written to (relative output paths are taken relative to it);
  /// "" = the directory of default_output, else the parent of map_dir (the run directory)
  std::string output_dir;
  double max_coordinate_m = 10000.0;  ///< input points beyond this (any axis) are refused as absurd [m], [1, 1e6]
  double map_voxel_m = 0.01;          ///< voxel [m] for the map when the request gives 0 (0 = none)
  double normal_radius_m = 0.0;       ///< [m]; 0 = 3 x point spacing
  int normal_min_neighbors = 5;
  bool smooth = true;                 ///< move points onto their local plane when estimating normals
  std::string color_mode = "height";  ///< "height" or "normal"
  int max_triangles_per_marker = 100000;
  int max_display_triangles = 2000000;  ///< larger meshes are shown by every k-th triangle (files keep all)
  std::string load_mesh;                ///< mesh (.stl/.ply) to show ("" = none); reloaded when it changes
  bool publish_map = false;             ///< publish map_dir's points, path, scan poses and base_link (viewing)
  /// map_dir must hold a map (its poses.csv) when the node starts: viewing a finished run, where an
  /// empty view of a directory that holds no run would only puzzle the user (view_run.launch)
  bool require_map = false;
  double map_cloud_voxel_m = 0.02;  ///< voxel [m] of the published map points (0 = all points)
  /// Points and triangles above this height [m] (map frame, floor at 0) are not shown: the ceiling would
  /// hide the room from rviz's view from above. Display only; meshes and files keep everything.
  double display_max_z_m = 2.0;
  double map_poll_s = 2.0;  ///< period [s] of checking map_dir and load_mesh for changes
  /// How build_mesh meshes the map (an empty input_path): "bpa" (Ball Pivoting of the map's points),
  /// "marching_cubes" (of the fused TSDF map, fused_map.h) or "fused_bpa" (Ball Pivoting of the fused
  /// map's surface points). A cloud file (input_path) is always meshed by Ball Pivoting. Default
  /// marching_cubes: nearer the true surfaces than bpa (room_10x8: median 2.6 against 9.1 mm) with a
  /// third of the triangles, in a quarter of the time and memory (docs/benchmarks.md).
  std::string mesh_method = "marching_cubes";
  double fused_voxel_m = 0.02;  ///< voxel of the fused map [m], [0.005, 0.5]
  double fused_carve_m = 0.2;   ///< free space carved before each hit along its beam [m], [0, 1000]
  /// ... and the rest of each beam in the voxels near some surface (FusedMapConfig::carve_far): removes
  /// the surfaces other scans see through from afar (a retroreflective leg's pillar, mixed pixels).
  bool fused_carve_far = true;
  /// Bound on the fused map's grids [MB], [1, 1e6]: a map whose fused grids would need more is fused
  /// again at 1.5 times the voxel, up to 4 times fused_voxel_m, and beyond that meshed by Ball
  /// Pivoting of its points (a WARN and the response's message say which).
  double fused_max_grid_mb = 1000.0;
  /// Threads that integrate the scans into the fused map, [1, 16] (FusedMapConfig::threads): each
  /// builds grids of its own within fused_max_grid_mb / fused_threads, merged afterwards.
  int fused_threads = 2;
  /// Bound on the error of the Marching Cubes mesh's decimation [m], [0, 0.1]; 0: none (decimate.h:
  /// the root mean square distance of a merged vertex to the planes of the faces it replaces).
  double mesh_decimate_error_m = 0.002;
  /// With a fused mesh_method: keep the fused map up to date during the mission (FusedMapTracker, a
  /// thread of its own checking map_dir every map_poll_s), so that build_mesh only integrates what is
  /// new and meshes. false: build_mesh integrates every scan then.
  bool fused_incremental = true;
  /// A scan whose map pose moved farther [m] / turned more [deg] since it was integrated is integrated
  /// again (FusedTrackerConfig).
  double fused_repose_m = 0.005;
  double fused_repose_deg = 0.1;
  /// Where a fused mesh_method writes the fused map (OpenVDB .vdb); "": fused_map.vdb beside the mesh.
  std::string fused_map_output;
  void validate() const;
  /// output_dir, or the directory it defaults to ("" when there is none).
  std::string allowedOutputDir() const;
};

class BpaMesherNode {
 public:
  /// Reads and validates the parameters, loads load_mesh; throws ConfigError / IoError naming the
  /// parameter or file that is wrong.
  BpaMesherNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  ~BpaMesherNode();
  BpaMesherNode(const BpaMesherNode&) = delete;
  BpaMesherNode& operator=(const BpaMesherNode&) = delete;

 private:
  /// The fused map's thread: brings the tracker up to map_dir whenever poses.csv changes.
  void trackLoop();
  /// One update of the tracker (the caller holds tracker_mutex_); drops the tracker, with a WARN, when
  /// it cannot go on (its grids would pass fused_max_grid_mb: build_mesh then integrates every scan).
  FusedTrackerUpdate updateTracker(const char* why);
  /// The fused map's settings at a voxel [m].
  FusedMapConfig fusedConfig(double voxel_m) const;
  /// Where the fused map of a mesh written to `output` goes.
  std::string vdbPath(const std::string& output) const;
  /// Decimates a Marching Cubes mesh by mesh_decimate_error_m; returns "; decimated from ..." for the
  /// message ("" when not).
  std::string decimate(TriangleMesh& mesh) const;
  /// The decimation's settings (none: not Marching Cubes, or mesh_decimate_error_m 0).
  std::optional<DecimateConfig> decimateConfig() const;
  /// "; decimated<how> from N within E mm in S s".
  std::string decimatedText(const DecimateStats& d, const std::string& how) const;
  /// The fused map's surface points on mesher/fused_cloud, cut at display_max_z_m.
  void publishFusedSurface(const std::vector<Eigen::Vector3f>& points);
  /// build_mesh from the tracker's map; false when there is no tracker (build_mesh integrates anew).
  bool buildFromTracker(const MesherConfig& mc, const std::string& output, scanstop_msgs::BuildMesh::Response& res);
  bool onBuildMesh(scanstop_msgs::BuildMesh::Request& req, scanstop_msgs::BuildMesh::Response& res);
  /// Loads the input, meshes, writes and publishes (the work of onBuildMesh after the request checks);
  /// every large buffer is released when it returns.
  void buildAndPublish(const scanstop_msgs::BuildMesh::Request& req, const MesherConfig& mc, const std::string& output,
                       scanstop_msgs::BuildMesh::Response& res);
  /// build_mesh of the map by a fused mesh_method (marching_cubes, fused_bpa).
  void buildFusedAndPublish(const MesherConfig& mc, const std::string& output, scanstop_msgs::BuildMesh::Response& res);
  /// The common end of both: writes the mesh to `output`, shows it, fills the response (message plus
  /// "; <skipped>" for each skipped item) and logs it.
  void finishMesh(const TriangleMesh& mesh, const std::string& output, size_t points, const std::string& message,
                  const std::vector<std::string>& skipped, scanstop_msgs::BuildMesh::Response& res);
  /// Shows `mesh` (the contents of `file`) to the current subscribers; later subscribers get it from
  /// `file` (onMarkerSubscriber).
  void publishMesh(const TriangleMesh& mesh, const std::string& file);
  void onMarkerSubscriber(const ros::SingleSubscriberPublisher& pub);
  visualization_msgs::MarkerArray markers(const TriangleMesh& mesh) const;
  void onMapTimer(const ros::WallTimerEvent&);
  void publishMapView();
  /// Publishes load_mesh when it exists and changed since the last call; throws IoError when it
  /// cannot be read.
  void reloadMesh();

  MesherNodeConfig config_;
  MeshColoring coloring_ = MeshColoring::kHeight;
  ros::ServiceServer build_srv_;
  ros::Publisher marker_pub_, cloud_pub_, path_pub_, poses_pub_, fused_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  ros::WallTimer map_timer_;
  std::string published_poses_;
  long long mesh_mtime_ns_ = -1;
  std::string shown_mesh_file_;  ///< the mesh on mesher/mesh_markers ("" = none yet)
  std::mutex tracker_mutex_;     ///< guards tracker_ and tracked_poses_
  std::unique_ptr<FusedMapTracker> tracker_;
  std::string tracked_poses_;  ///< poses.csv as the tracker last saw it
  std::atomic<bool> stop_{false};
  std::thread tracker_thread_;
};

}  // namespace mesher
}  // namespace scanstop
