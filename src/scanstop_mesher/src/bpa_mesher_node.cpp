#include "scanstop_mesher/bpa_mesher_node.h"

#include <malloc.h>
#include <sys/stat.h>

#include <chrono>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_mesher/decimate.h"
#include "scanstop_mesher/fused_map.h"

namespace scanstop {
namespace mesher {
namespace {

/// Throws IoError unless map_dir holds a map (a directory with a poses.csv), saying what to give instead.
void requireMapDirectory(const std::string& map_dir) {
  struct stat st;
  std::string problem;
  if (::stat(map_dir.c_str(), &st) != 0)
    problem = "does not exist";
  else if (!S_ISDIR(st.st_mode))
    problem = "is not a directory";
  else if (::stat((map_dir + "/poses.csv").c_str(), &st) != 0)
    problem = "holds no map (no poses.csv)";
  if (!problem.empty())
    throw IoError(map_dir, problem + "; require_map is set (viewing a run): give view_run.launch the run_dir of a " +
                               "finished run, e.g. run_dir:=$HOME/scanstop_runs/<world>");
}

}  // namespace

void MesherNodeConfig::validate() const {
  if (frame_id.empty()) throw ConfigError("parameter 'frame_id' is empty");
  requireInRange("map_voxel_m", map_voxel_m, 0.0, 10.0, "m");
  requireInRange("max_coordinate_m", max_coordinate_m, 1.0, 1e6, "m");
  requireNonNegative("normal_radius_m", normal_radius_m, "m");
  requireInRange("normal_min_neighbors", normal_min_neighbors, 3, 1000);
  requireOneOf("color_mode", color_mode, {"height", "normal"});
  requireInRange("max_triangles_per_marker", max_triangles_per_marker, 1, 10000000);
  requireInRange("max_display_triangles", max_display_triangles, 1, 100000000);
  requireNonNegative("map_cloud_voxel_m", map_cloud_voxel_m, "m");
  requirePositive("map_poll_s", map_poll_s, "s");
  requireInRange("display_max_z_m", display_max_z_m, 0.1, 1000.0, "m");
  requireOneOf("mesh_method", mesh_method, {"bpa", "marching_cubes", "fused_bpa"});
  requireInRange("fused_voxel_m", fused_voxel_m, 0.005, 0.5, "m");
  requireInRange("fused_carve_m", fused_carve_m, 0.0, 1000.0, "m");
  requireInRange("fused_max_grid_mb", fused_max_grid_mb, 1.0, 1e6, "MB");
  requireInRange("fused_threads", fused_threads, 1, 16);
  requireInRange("mesh_decimate_error_m", mesh_decimate_error_m, 0.0, 0.1, "m");
  requireInRange("fused_repose_m", fused_repose_m, 0.0, 1.0, "m");
  requireInRange("fused_repose_deg", fused_repose_deg, 0.0, 180.0, "deg");
  if (publish_map && map_dir.empty()) throw ConfigError("parameter 'publish_map' is true but 'map_dir' is empty");
  if (require_map && map_dir.empty()) throw ConfigError("parameter 'require_map' is true but 'map_dir' is empty");
  if (!default_output.empty()) {
    const std::string ext = fileExtension(default_output);
    if (ext != "stl" && ext != "ply")
      throw ConfigError("parameter 'default_output' = '" + default_output + "' must end in .stl or .ply");
  }
}

std::string MesherNodeConfig::allowedOutputDir() const {
  const auto dirname = [](std::string p) {
    while (p.size() > 1 && p.back() == '/') p.pop_back();
    const size_t slash = p.rfind('/');
    if (slash == std::string::npos) return std::string(".");
    return slash == 0 ? std::string("/") : p.substr(0, slash);
  };
  if (!output_dir.empty()) return output_dir;
  if (!default_output.empty()) return dirname(default_output);
  if (!map_dir.empty()) return dirname(map_dir);
  return "";
}

namespace {

/// The fused map's settings of the node's parameters at a voxel [m] (the truncation 3 voxels).
FusedMapConfig fusedConfigOf(const MesherNodeConfig& c, double voxel_m) {
  FusedMapConfig fc;
  fc.voxel_m = voxel_m;
  fc.truncation_m = 3.0 * voxel_m;
  fc.carve_m = c.fused_carve_m;
  fc.carve_far = c.fused_carve_far;
  fc.max_grid_mb = c.fused_max_grid_mb;
  fc.threads = c.fused_threads;
  return fc;
}

}  // namespace

BpaMesherNode::BpaMesherNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  MesherNodeConfig& c = config_;
  ros_params::ParamReader params(pnh, "bpa_mesher_node");
  params.known({"master_timeout_s", "end_launch_on_setup_error"});  // main()'s
  params.optional("map_dir", c.map_dir);
  params.optional("frame_id", c.frame_id);
  params.optional("default_output", c.default_output);
  params.optional("output_dir", c.output_dir);
  params.optional("max_coordinate_m", c.max_coordinate_m);
  params.optional("map_voxel_m", c.map_voxel_m);
  params.optional("normal_radius_m", c.normal_radius_m);
  params.optional("normal_min_neighbors", c.normal_min_neighbors);
  params.optional("smooth", c.smooth);
  params.optional("color_mode", c.color_mode);
  params.optional("max_triangles_per_marker", c.max_triangles_per_marker);
  params.optional("max_display_triangles", c.max_display_triangles);
  params.optional("load_mesh", c.load_mesh);
  params.optional("publish_map", c.publish_map);
  params.optional("require_map", c.require_map);
  params.optional("map_cloud_voxel_m", c.map_cloud_voxel_m);
  params.optional("display_max_z_m", c.display_max_z_m);
  params.optional("map_poll_s", c.map_poll_s);
  params.optional("mesh_method", c.mesh_method);
  params.optional("fused_voxel_m", c.fused_voxel_m);
  params.optional("fused_carve_m", c.fused_carve_m);
  params.optional("fused_carve_far", c.fused_carve_far);
  params.optional("fused_max_grid_mb", c.fused_max_grid_mb);
  params.optional("fused_threads", c.fused_threads);
  params.optional("fused_map_output", c.fused_map_output);
  params.optional("mesh_decimate_error_m", c.mesh_decimate_error_m);
  params.optional("fused_incremental", c.fused_incremental);
  params.optional("fused_repose_m", c.fused_repose_m);
  params.optional("fused_repose_deg", c.fused_repose_deg);
  params.rejectUnknown();
  c.validate();
  if (c.require_map) requireMapDirectory(c.map_dir);
  coloring_ = parseColoring(c.color_mode, "color_mode");

  // Relative names: meant to be remapped / pushed into a namespace.
  // Not latched: a latched mesh would keep ~120 bytes per shown triangle in this process for good.
  // A late subscriber (rviz started after the mesh) gets the mesh read back from its file instead.
  marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>(
      "mesher/mesh_markers", 1, [this](const ros::SingleSubscriberPublisher& pub) { onMarkerSubscriber(pub); },
      ros::SubscriberStatusCallback(), ros::VoidConstPtr(), false);
  build_srv_ = nh.advertiseService("mesher/build_mesh", &BpaMesherNode::onBuildMesh, this);
  // The fused map's surface points (a fused mesh_method), latched: one message per build.
  fused_pub_ = nh.advertise<sensor_msgs::PointCloud2>("mesher/fused_cloud", 1, true);
  if (!c.load_mesh.empty()) {
    reloadMesh();  // a file that exists but cannot be read stops the node
    if (mesh_mtime_ns_ < 0)
      ROS_WARN("bpa_mesher_node: %s does not exist (yet); showing it once it does", c.load_mesh.c_str());
  }
  if (c.publish_map) {
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("slam/map_cloud", 1, true);
    path_pub_ = nh.advertise<nav_msgs::Path>("slam/path", 1, true);
    poses_pub_ = nh.advertise<geometry_msgs::PoseArray>("mesher/scan_poses", 1, true);
    publishMapView();
  }
  if (c.publish_map || !c.load_mesh.empty())
    map_timer_ = nh.createWallTimer(ros::WallDuration(c.map_poll_s), &BpaMesherNode::onMapTimer, this);
  if (c.fused_incremental && isFusedMeshMethod(c.mesh_method) && !c.map_dir.empty()) {
    tracker_.reset(
        new FusedMapTracker(fusedConfig(c.fused_voxel_m), FusedTrackerConfig{c.fused_repose_m, c.fused_repose_deg}));
    tracker_thread_ = std::thread(&BpaMesherNode::trackLoop, this);
  }
}

BpaMesherNode::~BpaMesherNode() {
  stop_ = true;
  if (tracker_thread_.joinable()) tracker_thread_.join();
}

FusedMapConfig BpaMesherNode::fusedConfig(double voxel_m) const { return fusedConfigOf(config_, voxel_m); }

void BpaMesherNode::trackLoop() {
  while (!stop_) {
    for (double slept = 0.0; slept < config_.map_poll_s && !stop_; slept += 0.05)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (stop_) break;
    std::lock_guard<std::mutex> lock(tracker_mutex_);
    if (!tracker_) break;
    updateTracker("during the mission");
    if (tracker_ && fused_pub_.getNumSubscribers() > 0 && tracker_->scans() > 0) {
      PointCloud surface;  // the live map (the far carving counted, not applied), for the view
      for (const Eigen::Vector3f& p : tracker_->map().surfacePoints().points)
        if (p.z() <= config_.display_max_z_m) surface.points.push_back(p);
      surface.setUnorganized();
      fused_pub_.publish(ros_conv::toMsg(surface, config_.frame_id, ros::Time::now()));
    }
  }
}

FusedTrackerUpdate BpaMesherNode::updateTracker(const char* why) {
  FusedTrackerUpdate u;
  std::string poses;
  try {
    poses = readFile(config_.map_dir + "/poses.csv");
  } catch (const IoError&) {
    return u;  // no scan yet
  }
  if (poses == tracked_poses_) return u;
  try {
    u = tracker_->update(config_.map_dir);
    tracked_poses_ = poses;
    if (u.integrated + u.reintegrated > 0)
      ROS_INFO("bpa_mesher_node: fused map %s: %zu new and %zu moved scans integrated in %.2f s (%zu scans, %zu MB)",
               why, u.integrated, u.reintegrated, u.seconds, u.scans, tracker_->map().memoryBytes() / 1048576);
    for (const std::string& p : u.problems) ROS_WARN_THROTTLE(60.0, "bpa_mesher_node: fused map: %s", p.c_str());
  } catch (const GridBoundError& e) {
    ROS_WARN(
        "bpa_mesher_node: the fused map kept during the mission would pass fused_max_grid_mb = %.0f MB (%s): "
        "dropped; build_mesh fuses every scan then (in slabs)",
        config_.fused_max_grid_mb, e.what());
    tracker_.reset();
    malloc_trim(0);
  } catch (const IoError& e) {
    ROS_WARN_THROTTLE(30.0, "bpa_mesher_node: fused map: %s", e.what());  // tried again at the next change
  } catch (const std::exception& e) {                                     // nothing may leave the tracker's thread
    ROS_WARN(
        "bpa_mesher_node: the fused map kept during the mission failed (%s): dropped; build_mesh fuses every "
        "scan then",
        e.what());
    tracker_.reset();
    malloc_trim(0);
  }
  return u;
}

bool BpaMesherNode::buildFromTracker(const MesherConfig& mc, const std::string& output,
                                     scanstop_msgs::BuildMesh::Response& res) {
  const auto t0 = std::chrono::steady_clock::now();
  FusedMap fused;
  size_t scans = 0;
  FusedTrackerUpdate last;
  {
    std::lock_guard<std::mutex> lock(tracker_mutex_);
    if (!tracker_) return false;
    tracked_poses_.clear();  // catch up whatever the last poll saw
    last = updateTracker("at build_mesh");
    if (!tracker_ || tracker_->scans() == 0) return false;
    scans = tracker_->scans();
    fused = tracker_->snapshot();
  }
  const double catch_up_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto t_mesh = std::chrono::steady_clock::now();
  TriangleMesh mesh;
  std::vector<Eigen::Vector3f> surface;
  size_t surface_points = 0;
  if (config_.mesh_method == "marching_cubes") {
    mesh = fused.extractMesh();
    surface = mesh.vertices;  // one per surface cell
  } else {
    ScanPoints sp = fused.surfacePoints();
    surface_points = sp.size();
    if (sp.size() > 0) mesh = buildMesh(sp, mc).mesh;
    surface = std::move(sp.points);
  }
  if (mesh.faces.empty()) return false;  // nothing seen twice yet: the pass over the directory says why
  const double mesh_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_mesh).count();
  std::vector<std::string> skipped;
  const std::string vdb = vdbPath(output);
  std::string save_problem;
  std::thread saver([&] {  // written while the mesh is decimated
    try {
      fused.save(vdb);
    } catch (const IoError& e) {
      save_problem = e.what();
    }
  });
  const std::string decimated = decimate(mesh);
  saver.join();
  if (!save_problem.empty()) {
    ROS_ERROR("bpa_mesher_node: the fused map was not saved: %s", save_problem.c_str());
    skipped.push_back("the fused map was not saved: " + save_problem);
  }
  publishFusedSurface(surface);
  std::ostringstream msg;
  msg << mesh.faces.size() << " triangles by " << config_.mesh_method << " of the fused map of " << scans
      << " scans of map " << config_.map_dir << ", kept during the mission (voxel " << fused.config().voxel_m << " m, "
      << fused.activeVoxels() << " voxels, " << fused.memoryBytes() / 1048576 << " MB; brought up to date in "
      << catch_up_s << " s (" << last.integrated << " new, " << last.reintegrated << " moved scans), meshing " << mesh_s
      << " s" << decimated << "; fused map in " << vdb << ", " << surface.size() << " surface points)";
  finishMesh(mesh, output, surface_points, msg.str(), skipped, res);
  return true;
}

void BpaMesherNode::reloadMesh() {
  struct stat st;
  if (::stat(config_.load_mesh.c_str(), &st) != 0) return;
  const long long mtime = static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
  if (mtime == mesh_mtime_ns_) return;
  const TriangleMesh mesh = readMesh(config_.load_mesh);
  mesh_mtime_ns_ = mtime;
  ROS_INFO("bpa_mesher_node: showing %zu triangles from %s", mesh.faces.size(), config_.load_mesh.c_str());
  publishMesh(mesh, config_.load_mesh);
}

void BpaMesherNode::onMarkerSubscriber(const ros::SingleSubscriberPublisher& pub) {
  if (shown_mesh_file_.empty()) return;
  try {
    const TriangleMesh mesh = readMesh(shown_mesh_file_);
    pub.publish(markers(mesh));
  } catch (const std::exception& e) {
    ROS_WARN("bpa_mesher_node: cannot show %s to %s: %s", shown_mesh_file_.c_str(), pub.getSubscriberName().c_str(),
             e.what());
  }
  malloc_trim(0);
}

bool BpaMesherNode::onBuildMesh(scanstop_msgs::BuildMesh::Request& req, scanstop_msgs::BuildMesh::Response& res) {
  const auto t0 = std::chrono::steady_clock::now();
  res.success = false;
  try {
    // Every check before any work and before anything is written or published.
    std::string output;
    MesherConfig mc;
    try {
      const std::string requested = req.output_path.empty() ? config_.default_output : req.output_path;
      if (requested.empty()) throw ConfigError("output_path is empty and parameter 'default_output' is not set");
      output = resolveOutputPath(requested, config_.allowedOutputDir());
      requireInRange("voxel_m", req.voxel_m, 0.0, 10.0, "m");
      mc.radii_m.assign(req.radii.begin(), req.radii.end());
      mc.normal_radius_m = config_.normal_radius_m;
      mc.normal_min_neighbors = config_.normal_min_neighbors;
      mc.smooth = config_.smooth;
      mc.voxel_m = req.input_path.empty() && req.voxel_m == 0.0 ? config_.map_voxel_m : req.voxel_m;
      mc.validate();
      if (req.input_path.empty() && config_.map_dir.empty())
        throw ConfigError("input_path is empty and parameter 'map_dir' is not set");
    } catch (const ConfigError& e) {
      throw ConfigError(std::string("bad request: ") + e.what());
    }
    buildAndPublish(req, mc, output, res);
  } catch (const std::exception& e) {
    res.message = e.what();
    ROS_ERROR("bpa_mesher_node: build_mesh failed: %s", e.what());
  }
  // The points, the mesh and the marker messages are gone by now; hand the freed heap back to the
  // system so that the node returns to its idle size (plus the latched display) after every mesh.
  malloc_trim(0);
  res.duration_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return true;
}

void BpaMesherNode::buildAndPublish(const scanstop_msgs::BuildMesh::Request& req, const MesherConfig& mc,
                                    const std::string& output, scanstop_msgs::BuildMesh::Response& res) {
  std::string fallback;  // why a fused mesh_method became Ball Pivoting of the points
  if (req.input_path.empty() && isFusedMeshMethod(config_.mesh_method)) {
    try {
      buildFusedAndPublish(mc, output, res);
      return;
    } catch (const GridBoundError& e) {
      fallback = std::string("the fused map needs more than fused_max_grid_mb = ") +
                 std::to_string(static_cast<long>(config_.fused_max_grid_mb)) +
                 " MB even at 4 times fused_voxel_m: meshed by Ball Pivoting of the map's points instead (" + e.what() +
                 ")";
      ROS_WARN("bpa_mesher_node: %s", fallback.c_str());
      malloc_trim(0);  // the grids built so far are gone
    }
  }
  ScanPoints points;
  std::string source;
  std::vector<std::string> skipped;
  if (req.input_path.empty()) {
    points = loadMapDirectory(config_.map_dir, &skipped);
    source = "map " + config_.map_dir;
  } else {
    points = fromCloud(readCloud(req.input_path), Eigen::Vector3f::Zero());
    source = req.input_path;
  }
  for (const std::string& s : skipped) ROS_ERROR("bpa_mesher_node: %s", s.c_str());
  const std::string problem = pointsProblem(points, config_.max_coordinate_m);
  if (!problem.empty()) throw std::invalid_argument("bad input " + source + ": " + problem);
  const MesherResult r = buildMesh(points, mc);
  std::ostringstream msg;
  msg << r.mesh.faces.size() << " triangles from " << r.points << " of " << r.input_points << " points of " << source
      << " (radii";
  for (double x : r.radii_m) msg << " " << x;
  msg << " m; " << r.topology.nonmanifold_edges << " non-manifold edges, " << r.topology.nonmanifold_vertices
      << " non-manifold vertices)";
  if (!fallback.empty()) skipped.push_back(fallback);
  finishMesh(r.mesh, output, r.points, msg.str(), skipped, res);
}

void BpaMesherNode::finishMesh(const TriangleMesh& mesh, const std::string& output, size_t points,
                               const std::string& message, const std::vector<std::string>& skipped,
                               scanstop_msgs::BuildMesh::Response& res) {
  writeMesh(output, mesh);
  publishMesh(mesh, output);
  res.success = true;
  res.points = static_cast<uint32_t>(points);
  res.triangles = static_cast<uint32_t>(mesh.faces.size());
  res.file = output;
  res.message = message;
  for (const std::string& s : skipped) res.message += "; " + s;
  ROS_INFO("bpa_mesher_node: %s -> %s", res.message.c_str(), output.c_str());
}

std::string BpaMesherNode::vdbPath(const std::string& output) const {
  // The fused map is kept with the run: beside the mesh unless fused_map_output says where.
  return !config_.fused_map_output.empty() ? config_.fused_map_output
                                           : output.substr(0, output.find_last_of('/') + 1) + "fused_map.vdb";
}

std::optional<DecimateConfig> BpaMesherNode::decimateConfig() const {
  if (config_.mesh_method != "marching_cubes" || config_.mesh_decimate_error_m <= 0.0) return std::nullopt;
  DecimateConfig dc;
  dc.max_error_m = config_.mesh_decimate_error_m;
  return dc;
}

std::string BpaMesherNode::decimatedText(const DecimateStats& d, const std::string& how) const {
  std::ostringstream out;
  out << "; decimated" << how << " from " << d.faces_before << " within " << config_.mesh_decimate_error_m * 1000.0
      << " mm in " << d.seconds << " s";
  return out.str();
}

std::string BpaMesherNode::decimate(TriangleMesh& mesh) const {
  const std::optional<DecimateConfig> dc = decimateConfig();
  if (!dc) return "";
  return decimatedText(decimateMesh(mesh, *dc), "");
}

void BpaMesherNode::publishFusedSurface(const std::vector<Eigen::Vector3f>& points) {
  PointCloud surface;
  for (const Eigen::Vector3f& p : points)
    if (p.z() <= config_.display_max_z_m) surface.points.push_back(p);  // the ceiling cut away for the view
  surface.setUnorganized();
  fused_pub_.publish(ros_conv::toMsg(surface, config_.frame_id, ros::Time::now()));
}

void BpaMesherNode::buildFusedAndPublish(const MesherConfig& mc, const std::string& output,
                                         scanstop_msgs::BuildMesh::Response& res) {
  if (buildFromTracker(mc, output, res)) return;
  FusedMapConfig fc = fusedConfig(config_.fused_voxel_m);
  std::vector<std::string> skipped;
  const std::string vdb = vdbPath(output);
  const std::optional<DecimateConfig> decimate_config = decimateConfig();  // slabs: each decimated alone
  // A map too large for the grids at fused_voxel_m is built in slabs along x (meshFusedMapDirectory);
  // one whose 1 m slabs do not fit either is fused with coarser voxels (the grids' memory falls with
  // about the square of the voxel: a band of voxels around every surface), up to 4 times
  // fused_voxel_m; beyond that GridBoundError goes to the caller (Ball Pivoting).
  FusedMesh r;
  for (double voxel = config_.fused_voxel_m;; voxel *= 1.5) {
    fc.voxel_m = voxel;
    fc.truncation_m = 3.0 * voxel;
    skipped.clear();
    try {
      r = meshFusedMapDirectory(config_.map_dir, fc, config_.mesh_method, mc, &skipped, vdb, 1.0,
                                decimate_config ? &*decimate_config : nullptr);
      break;
    } catch (const GridBoundError& e) {
      if (voxel * 1.5 > 4.0 * config_.fused_voxel_m + 1e-9) throw;
      ROS_WARN(
          "bpa_mesher_node: the fused map at a %.3f m voxel needs more than fused_max_grid_mb = %.0f MB even in 1 m "
          "slabs: fusing again at %.3f m",
          voxel, config_.fused_max_grid_mb, voxel * 1.5);
      malloc_trim(0);
    }
  }
  std::string coarser;
  if (r.slabs > 1)
    ROS_WARN(
        "bpa_mesher_node: the fused map of %s would pass fused_max_grid_mb = %.0f MB as a whole: built and "
        "meshed in %zu slabs along x (the largest %.0f MB), no .vdb of the whole",
        config_.map_dir.c_str(), config_.fused_max_grid_mb, r.slabs, r.memory_bytes / 1048576.0);
  if (fc.voxel_m != config_.fused_voxel_m) {
    std::ostringstream why;
    why << "fused at a " << fc.voxel_m << " m voxel: at " << config_.fused_voxel_m
        << " m (fused_voxel_m) the grids needed more than fused_max_grid_mb = " << config_.fused_max_grid_mb << " MB";
    ROS_WARN("bpa_mesher_node: %s", why.str().c_str());
    coarser = why.str();
  }
  for (const std::string& s : skipped) ROS_ERROR("bpa_mesher_node: %s", s.c_str());
  if (!coarser.empty()) skipped.push_back(coarser);
  if (!r.save_problem.empty()) {
    ROS_ERROR("bpa_mesher_node: the fused map was not saved: %s", r.save_problem.c_str());
    skipped.push_back("the fused map was not saved: " + r.save_problem);
  }
  const std::string decimated =
      r.decimated.faces_before > 0 ? decimatedText(r.decimated, " slab by slab") : decimate(r.mesh);
  publishFusedSurface(r.surface);
  std::ostringstream msg;
  msg << r.mesh.faces.size() << " triangles by " << config_.mesh_method << " of the fused map of " << r.scans
      << " scans of map " << config_.map_dir << " (voxel " << fc.voxel_m << " m, " << r.voxels << " voxels, "
      << r.memory_bytes / 1048576 << " MB; integration " << r.integrate_s << " s, meshing " << r.mesh_s << " s"
      << decimated << "; "
      << (r.slabs > 1 ? std::string("built in ") + std::to_string(r.slabs) +
                            " slabs along x, the largest within fused_max_grid_mb: no .vdb of the whole"
          : r.save_problem.empty() ? "fused map in " + vdb
                                   : std::string("fused map not saved"))
      << ", " << r.surface.size() << " surface points)";
  finishMesh(r.mesh, output, r.surface_points, msg.str(), skipped, res);
}

void BpaMesherNode::publishMesh(const TriangleMesh& mesh, const std::string& file) {
  shown_mesh_file_ = file;
  if (mesh.faces.size() > static_cast<size_t>(config_.max_display_triangles))
    ROS_INFO("bpa_mesher_node: %zu triangles: showing every %zu-th (max_display_triangles = %d)", mesh.faces.size(),
             (mesh.faces.size() + config_.max_display_triangles - 1) / config_.max_display_triangles,
             config_.max_display_triangles);
  if (marker_pub_.getNumSubscribers() > 0) marker_pub_.publish(markers(mesh));
}

visualization_msgs::MarkerArray BpaMesherNode::markers(const TriangleMesh& mesh) const {
  return meshToMarkers(mesh, config_.frame_id, ros::Time::now(), coloring_,
                       static_cast<size_t>(config_.max_triangles_per_marker),
                       static_cast<size_t>(config_.max_display_triangles), static_cast<float>(config_.display_max_z_m));
}

void BpaMesherNode::onMapTimer(const ros::WallTimerEvent&) {
  if (config_.publish_map) try {
      publishMapView();
    } catch (const std::exception& e) {
      ROS_WARN_THROTTLE(30.0, "bpa_mesher_node: cannot show the map: %s", e.what());
    }
  if (!config_.load_mesh.empty()) try {
      reloadMesh();
    } catch (const std::exception& e) {
      ROS_WARN_THROTTLE(30.0, "bpa_mesher_node: cannot show the mesh: %s", e.what());
    }
}

void BpaMesherNode::publishMapView() {
  std::string poses;
  try {
    poses = readFile(config_.map_dir + "/poses.csv");
  } catch (const IoError&) {
    return;  // no scan yet
  }
  if (poses == published_poses_) return;
  const MapDirectory map(config_.map_dir);
  const ros::Time stamp = ros::Time::now();
  const ScanPoints points = voxelDownsample(loadMapDirectory(config_.map_dir), config_.map_cloud_voxel_m);
  PointCloud cloud;
  for (const Eigen::Vector3f& p : points.points)
    if (p.z() <= config_.display_max_z_m) cloud.points.push_back(p);  // the ceiling cut away for the view
  cloud.setUnorganized();
  cloud_pub_.publish(ros_conv::toMsg(cloud, config_.frame_id, stamp));
  nav_msgs::Path path;
  geometry_msgs::PoseArray scan_poses;
  path.header.frame_id = scan_poses.header.frame_id = config_.frame_id;
  path.header.stamp = scan_poses.header.stamp = stamp;
  for (const MapScanInfo& s : map.scans()) {
    path.poses.push_back(ros_conv::toPoseStamped(s.map_pose, config_.frame_id, stamp));
    scan_poses.poses.push_back(ros_conv::toPoseMsg(s.map_pose));
  }
  path_pub_.publish(path);
  poses_pub_.publish(scan_poses);
  // The robot where it took the last scan (nobody else publishes base_link when viewing a run).
  static_tf_.sendTransform(ros_conv::toTransformMsg(map.scans().back().map_pose, config_.frame_id, "base_link", stamp));
  published_poses_ = poses;
  ROS_INFO("bpa_mesher_node: showing %zu scans, %zu map points", map.size(), cloud.size());
}

}  // namespace mesher
}  // namespace scanstop
