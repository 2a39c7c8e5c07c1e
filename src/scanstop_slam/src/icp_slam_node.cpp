// icp_slam_node wires IcpSlam to ROS: it serves slam/register_scan, writes the map directory after
// every scan, and publishes the corrected pose, tf map -> odom, the path of scan poses, each
// registered scan once in the map frame, and a voxel-downsampled map cloud.
// Offline mode (subscribe_scans, launch/replay.launch): scans arrive on scanner/last_scan and the
// odometry pose at scan time comes from the odom topic (a rosbag played into the node).
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <scanstop_msgs/RegisterScan.h>
#include <scanstop_msgs/RegisteredScan.h>
#include <tf2_ros/transform_broadcaster.h>

#include <deque>
#include <memory>
#include <mutex>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/launch_control.h"
#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_slam/icp_slam.h"
#include "scanstop_slam/request_check.h"

namespace scanstop {
namespace slam {

class IcpSlamNode {
 public:
  IcpSlamNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
    SlamConfig config;
    ros_params::ParamReader params(pnh, "icp_slam_node");
    const auto optional = [&](const std::string& name, auto& value) { params.optional(name, value); };
    double master_timeout_s =
        30.0;  // main() reads it for the master watchdog; a known name here (and its type checked)
    optional("master_timeout_s", master_timeout_s);
    bool end_launch = false;  // read by main() after a start-up error; a known name here
    optional("end_launch_on_setup_error", end_launch);
    std::string mode = "3dof";
    optional("mode", mode);
    requireMode(pnh, mode);
    config.icp.six_dof = mode == "6dof";
    std::string method = toString(config.icp.method);  // point_to_point | point_to_plane
    optional("method", method);
    config.icp.method = parseIcpMethod(method, pnh.resolveName("method"));
    optional("degeneracy_ratio", config.icp.degeneracy_ratio);
    optional("degeneracy_remap", config.icp.degeneracy_remap);
    optional("prior_all_directions", config.icp.prior_all_directions);
    optional("information_points", config.icp.information_points);
    optional("information_sigma_m", config.icp.information_sigma_m);
    optional("odometry_prior", config.odometry_prior);
    optional("prior_sigma_m", config.prior_sigma_m);
    optional("prior_sigma_per_m", config.prior_sigma_per_m);
    params.degrees("prior_sigma_deg", config.prior_sigma_rad, 1e-4, 180.0);
    optional("prior_sigma_rad_per_rad", config.prior_sigma_rad_per_rad);
    optional("prior_gate", config.prior_gate);
    optional("odometry_gate", config.odometry_gate);
    optional("odometry_gate_rms_ratio", config.odometry_gate_rms_ratio);
    optional("odometry_gate_weak_rms_ratio", config.odometry_gate_weak_rms_ratio);
    optional("failure_retry_degeneracy_ratio", config.failure_retry_degeneracy_ratio);
    params.degrees("prior_sigma_deg_per_m", config.prior_sigma_rad_per_m, 0.0, 57.0);
    optional("c_max_m", config.icp.c_max_m);
    optional("t_c_m", config.icp.t_c_m);
    params.degrees("r_c_deg", config.icp.r_c_rad, 1e-7, 45.0);
    optional("max_iterations", config.icp.max_iterations);
    optional("min_correspondences", config.icp.min_correspondences);
    optional("min_overlap", config.icp.min_overlap);
    optional("max_correction_m", config.icp.max_correction_m);
    optional("max_correction_rad", config.icp.max_correction_rad);
    optional("source_voxel_m", config.source_voxel_m);
    optional("source_centroids", config.source_centroids);
    optional("odom_scale_estimation", config.odom_scale_estimation);
    optional("odom_scale_min_travel_m", config.odom_scale_min_travel_m);
    optional("odom_scale_both_ends", config.odom_scale_both_ends);
    optional("odom_turn_estimation", config.odom_turn_estimation);
    optional("odom_turn_min_total_rad", config.odom_turn_min_total_rad);
    optional("max_points_per_voxel", config.max_points_per_voxel);
    optional("map_spacing_m", config.map_spacing_m);
    optional("coarse_c_max_m", config.coarse_c_max_m);
    optional("coarse_point_to_point", config.coarse_point_to_point);
    optional("refine_t_c_m", config.refine_t_c_m);
    params.degrees("refine_r_c_deg", config.refine_r_c_rad, 1e-7, 0.5);
    optional("refine_max_iterations", config.refine_max_iterations);
    optional("refine_source_voxel_m", config.refine_source_voxel_m);
    optional("refine_max_correction_m", config.refine_max_correction_m);
    params.degrees("refine_max_correction_deg", config.refine_max_correction_rad, 0.0, 180.0);
    optional("same_side", config.icp.same_side);
    optional("accelerate", config.icp.accelerate);
    optional("ignore_horizontal", config.icp.ignore_horizontal);
    optional("max_point_distance_m", config.max_point_distance_m);
    optional("max_odom_jump_m", config.max_odom_jump_m);
    // Global relaxation (SlamConfig::relax*, icp_slam.h).
    optional("relax", config.relax);
    optional("relax_neighbours", config.relax_neighbours);
    optional("relax_loop_candidates", config.relax_loop_candidates);
    optional("relax_loop_min_gap", config.relax_loop_min_gap);
    optional("relax_max_distance_m", config.relax_max_distance_m);
    optional("relax_voxel_m", config.relax_voxel_m);
    optional("relax_min_overlap", config.relax_min_overlap);
    optional("relax_max_rms_m", config.relax_max_rms_m);
    optional("relax_update_m", config.relax_update_m);
    params.degrees("relax_update_deg", config.relax_update_rad, 0.0, 180.0);
    optional("relax_loss", config.graph.loss);
    optional("relax_loss_scale", config.graph.loss_scale);
    optional("max_cloud_points", max_cloud_points_);
    optional("map_cloud_voxel_m", map_cloud_voxel_m_);
    optional("map_cloud_max_z_m", map_cloud_max_z_m_);
    optional("sensor_height_m", sensor_height_m_);
    optional("map_frame", map_frame_);
    optional("odom_frame", odom_frame_);
    optional("base_frame", base_frame_);
    std::string map_dir;
    optional("map_dir", map_dir);
    bool subscribe_scans = false;
    optional("subscribe_scans", subscribe_scans);
    params.rejectUnknown();
    try {
      config.validate();
      requireInRange("max_cloud_points", max_cloud_points_, 1, 1e8);
      requireInRange("map_cloud_voxel_m", map_cloud_voxel_m_, 0.0, 10.0, "m");
      requireInRange("map_cloud_max_z_m", map_cloud_max_z_m_, 0.1, 1000.0, "m");
      requireInRange("sensor_height_m", sensor_height_m_, -10.0, 10.0, "m");
    } catch (const ConfigError& e) {
      throw ConfigError(std::string(e.what()) + " (in namespace " + pnh.getNamespace() + ")");
    }
    params.frames({{"map_frame", map_frame_}, {"odom_frame", odom_frame_}, {"base_frame", base_frame_}});
    slam_ = std::make_unique<IcpSlam>(config, map_dir);
    for (const SkippedScan& s : slam_->skippedScans()) {
      const std::string what = s.reason.compare(0, s.file.size(), s.file) == 0 ? s.reason : s.file + ": " + s.reason;
      if (what.find("restored from poses_journal.csv") != std::string::npos)  // the scan ledger kept it: loaded
        ROS_WARN("icp_slam_node: map directory problem, repaired: %s", what.c_str());
      else
        ROS_ERROR("icp_slam_node: map directory problem, skipped: %s", what.c_str());
    }
    if (slam_->scanCount() > 0)
      ROS_INFO("icp_slam_node: resumed the map in %s with %zu scans (%zu skipped, %zu map points)", map_dir.c_str(),
               slam_->scanCount(), slam_->skippedScans().size(), slam_->map().size());

    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("slam/pose", 10, true);
    path_pub_ = nh.advertise<nav_msgs::Path>("slam/path", 1, true);
    scan_pub_ = nh.advertise<scanstop_msgs::RegisteredScan>("slam/registered_scan", 50);
    map_pub_ = nh.advertise<sensor_msgs::PointCloud2>("slam/map_cloud", 1, true);
    server_ = nh.advertiseService("slam/register_scan", &IcpSlamNode::onRegister, this);
    if (subscribe_scans) {
      // Every scan is kept (a registration takes about a second; scans come tens of seconds apart).
      odom_sub_ = nh.subscribe("odom", 200, &IcpSlamNode::onOdom, this);
      scan_sub_ = nh.subscribe("scanner/last_scan", 100, &IcpSlamNode::onScan, this);
    }
    timer_ = nh.createWallTimer(ros::WallDuration(1.0), [this](const ros::WallTimerEvent&) { publishTf(false); });
    path_.header.frame_id = map_frame_;
    rebuildMapCloud();  // a resumed map's points
    if (const MapDirectory* dir = slam_->mapDirectory()) {
      for (const MapScanInfo& s : dir->scans())
        path_.poses.push_back(ros_conv::toPoseStamped(s.map_pose, map_frame_, ros::Time(s.stamp_s)));
      publishMap(ros::Time::now());
    }
    publishTf(true);
  }

 private:
  static void requireMode(const ros::NodeHandle& pnh, const std::string& mode) {
    if (mode != "3dof" && mode != "6dof")
      throw ConfigError("parameter '" + pnh.resolveName("mode") + "' = '" + mode + "' must be 3dof or 6dof");
  }

  void publishTf(bool force) {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time now = ros::Time::now();
    if (!force && now <= last_tf_stamp_) return;  // simulated time stands still between steps
    last_tf_stamp_ = now;
    tf_.sendTransform(ros_conv::toTransformMsg(slam_->mapFromOdom(), map_frame_, odom_frame_, now));
  }

  /// Adds points (map frame) to slam/map_cloud's cloud: below map_cloud_max_z_m (the ceiling cut
  /// away for the view), one per map_cloud_voxel_m voxel.
  void addToMapCloud(const std::vector<Eigen::Vector3f>& points) {
    std::vector<Eigen::Vector3f> below;
    below.reserve(points.size());
    for (const Eigen::Vector3f& p : points)
      if (p.z() <= map_cloud_max_z_m_) below.push_back(p);
    map_cloud_.add(below);
  }

  /// slam/map_cloud's cloud anew from the whole map (at start, and when the relaxation moved poses).
  void rebuildMapCloud() {
    map_cloud_ = VoxelDownsampler(map_cloud_voxel_m_);
    addToMapCloud(slam_->map().points());
  }

  void publishMap(const ros::Time& stamp) {
    PointCloud cloud;
    cloud.points = map_cloud_.points();
    cloud.setUnorganized();
    map_pub_.publish(ros_conv::toMsg(cloud, map_frame_, stamp));
    path_.header.stamp = stamp;
    path_pub_.publish(path_);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    odom_.push_back(msg);
    if (odom_.size() > 2000) odom_.pop_front();
  }

  /// Offline mode: the scan is registered at the latest odometry pose not after its stamp (the robot
  /// stands still while it scans); without one the scan is dropped with a warning.
  void onScan(const sensor_msgs::PointCloud2::ConstPtr& msg) {
    const nav_msgs::Odometry::ConstPtr* best = nullptr;
    for (const auto& o : odom_)
      if (o->header.stamp <= msg->header.stamp && (!best || o->header.stamp >= (*best)->header.stamp)) best = &o;
    if (!best) {
      ROS_WARN("icp_slam_node: dropped the scan stamped %.3f: no odometry on %s at or before it",
               msg->header.stamp.toSec(), odom_sub_.getTopic().c_str());
      return;
    }
    scanstop_msgs::RegisterScan::Request req;
    scanstop_msgs::RegisterScan::Response res;
    req.cloud = *msg;
    req.odom_pose.header = (*best)->header;
    req.odom_pose.pose = (*best)->pose.pose;
    onRegister(req, res);
    if (!res.success)
      ROS_WARN("icp_slam_node: scan from %s not registered: %s", scan_sub_.getTopic().c_str(), res.message.c_str());
  }

  /// Everything about a request that can be checked before it touches the map; "" when it is fine.
  std::string requestProblem(const scanstop_msgs::RegisterScan::Request& req) const {
    std::string p = frameProblem(req.cloud.header.frame_id, base_frame_, "the cloud");
    if (p.empty()) p = frameProblem(req.odom_pose.header.frame_id, odom_frame_, "odom_pose");
    if (p.empty()) p = cloudLayoutProblem(req.cloud, static_cast<size_t>(max_cloud_points_));
    if (p.empty()) p = poseProblem(req.odom_pose.pose, "odom_pose");
    return p;
  }

  bool onRegister(scanstop_msgs::RegisterScan::Request& req, scanstop_msgs::RegisterScan::Response& res) {
    const auto refuse = [&](const std::string& why) {
      res.success = false;
      res.message = "bad request: " + why;
      ROS_WARN("icp_slam_node: refused a scan: %s", res.message.c_str());
      return true;
    };
    PointCloud scan;
    Pose2D odom;
    try {
      const std::string problem = requestProblem(req);
      if (!problem.empty()) return refuse(problem);
      scan = ros_conv::fromMsg(req.cloud);
      odom = ros_conv::fromPoseMsg(req.odom_pose.pose);
    } catch (const std::exception& e) {
      return refuse(e.what());
    }
    Registration r;
    try {
      std::lock_guard<std::mutex> lock(mutex_);
      r = slam_->registerScan(scan, odom, Eigen::Vector3d(0, 0, sensor_height_m_), req.cloud.header.stamp.toSec());
    } catch (const std::invalid_argument& e) {
      return refuse(e.what());
    } catch (const std::exception& e) {
      res.success = false;
      res.message = std::string("could not store the scan: ") + e.what();
      ROS_ERROR("icp_slam_node: %s", res.message.c_str());
      return true;
    }
    const ros::Time stamp = req.cloud.header.stamp.isZero() ? ros::Time::now() : req.cloud.header.stamp;
    res.success = true;
    res.converged = r.converged;
    res.message = r.converged ? "" : "registration failed, kept the odometry pose: " + r.failure;
    res.duration_s = r.time_s;
    res.map_pose = ros_conv::toPoseStamped(r.map_pose, map_frame_, stamp);
    res.iterations = static_cast<uint32_t>(r.iterations);
    res.correspondences = static_cast<uint32_t>(r.correspondences);
    res.rms_m = r.rms_m;
    res.overlap = r.overlap;
    res.scan_index = r.index;
    if (r.converged)
      ROS_INFO(
          "icp_slam_node: scan %u at %s after %d iterations, %zu correspondences, rms %.1f mm, %.2f s, "
          "condition %.3g%s%s, odometry scale %.4f, turn scale %.4f, %.2f deg per leg, prior %.1f sigma, weak "
          "directions %.1f cm %.2f deg from the remap",
          r.index, r.map_pose.toString().c_str(), r.iterations, r.correspondences, r.rms_m * 1000, r.time_s,
          r.condition, r.degenerate ? " (degenerate" : "",
          r.degenerate ? (r.remapped ? (slam_->config().odometry_prior ? ", held by the odometry prior)"
                                                                       : ", guess kept along the weak direction)")
                                     : ")")
                       : "",
          r.odom_scale, r.odom_turn_scale, r.odom_leg_turn_rad * 180 / M_PI, r.prior_distance, r.weak_gain_m * 100,
          r.weak_gain_rad * 180 / M_PI);
    else
      ROS_WARN("icp_slam_node: scan %u: %s", r.index, res.message.c_str());
    if (r.prior_rejected)
      ROS_WARN(
          "icp_slam_node: scan %u: weighed against the odometry prior the registration ended %.1f sigma from "
          "it (beyond prior_gate %.1f): registered again keeping the guess along weak directions",
          r.index, r.prior_distance, slam_->config().prior_gate);
    if (r.gate_retried)
      ROS_WARN(
          "icp_slam_node: scan %u: the registration ended %.1f sigma from the odometry guess (beyond "
          "odometry_gate %.1f): registered again without the coarse stage; %s",
          r.index, r.guess_distance, slam_->config().odometry_gate,
          r.gate_widened    ? "it did not land within the gate either; registered once more keeping the guess along "
                              "more weakly held directions (failure_retry_degeneracy_ratio): that result stands"
          : r.gate_replaced ? "that result stands"
                            : "neither it nor a third registration keeping the guess along more weakly held "
                              "directions landed within the gate: the first stands");
    if (r.failure_retried)
      ROS_WARN(
          "icp_slam_node: scan %u: the registration failed (%s): registered again with degeneracy_ratio %.3f "
          "(failure_retry_degeneracy_ratio); %s",
          r.index, r.first_failure.c_str(), slam_->config().failure_retry_degeneracy_ratio,
          r.failure_replaced ? "it converged: that result stands"
                             : "it did not converge within the gate either: the odometry pose is kept");
    if (r.refine_rejected)
      ROS_WARN(
          "icp_slam_node: scan %u: the refinement stage moved the pose %.1f cm, %.2f deg (beyond "
          "refine_max_correction %.1f cm, %.2f deg): kept the thesis stage's result",
          r.index, r.refine_moved_m * 100, r.refine_moved_rad * 180 / M_PI,
          slam_->config().refine_max_correction_m * 100, slam_->config().refine_max_correction_rad * 180 / M_PI);

    if (slam_->config().relax) {
      if (r.relaxed)
        ROS_INFO(
            "icp_slam_node: scan %u: relaxation (%d of %d pairwise edges) moved %zu earlier poses, at most "
            "%.1f cm %.2f deg, in %.2f s",
            r.index, r.relax_edges, r.relax_edges_tried, r.relax_moved, r.relax_max_moved_m * 100,
            r.relax_max_moved_rad * 180 / M_PI, r.relax_time_s);
      if (!r.relax_problem.empty()) ROS_WARN("icp_slam_node: scan %u: %s", r.index, r.relax_problem.c_str());
    }

    pose_pub_.publish(res.map_pose);
    publishTf(true);  // map -> odom from the last scan's (corrected) pose
    if (r.relaxed) {
      // Earlier poses moved: the whole path anew from the corrected poses.
      path_.poses.clear();
      for (const ScanPose& p : slam_->poses())
        path_.poses.push_back(
            p.index == r.index ? res.map_pose : ros_conv::toPoseStamped(p.map_pose, map_frame_, ros::Time(p.stamp_s)));
    } else {
      path_.poses.push_back(res.map_pose);
    }
    scanstop_msgs::RegisteredScan out;
    out.header.frame_id = map_frame_;
    out.header.stamp = stamp;
    out.scan_index = r.index;
    out.pose = res.map_pose;
    const Eigen::Vector3d origin = r.map_pose.toIsometry3d() * Eigen::Vector3d(0, 0, sensor_height_m_);
    out.sensor_origin.x = origin.x();
    out.sensor_origin.y = origin.y();
    out.sensor_origin.z = origin.z();
    const PointCloud in_map = transformCloud(removeNonFinite(scan), r.map_pose.toIsometry3f());
    out.cloud = ros_conv::toMsg(in_map, map_frame_, stamp);
    out.registration_ok = r.converged;
    scan_pub_.publish(out);
    // The map's view grows by this scan; after a relaxation every earlier scan moved too.
    if (r.relaxed)
      rebuildMapCloud();
    else
      addToMapCloud(in_map.points);
    publishMap(stamp);
    return true;
  }

  std::unique_ptr<IcpSlam> slam_;
  std::mutex mutex_;
  int max_cloud_points_ = 5000000;
  double map_cloud_voxel_m_ = 0.05;
  VoxelDownsampler map_cloud_{0.05};  ///< slam/map_cloud's points (map frame)
  double map_cloud_max_z_m_ = 2.0;    ///< [m] slam/map_cloud leaves out points above (the ceiling hides the room)
  double sensor_height_m_ = 0.45;
  std::string map_frame_ = "map", odom_frame_ = "odom", base_frame_ = "base_link";
  ros::Publisher pose_pub_, path_pub_, scan_pub_, map_pub_;
  ros::ServiceServer server_;
  ros::Subscriber odom_sub_, scan_sub_;
  std::deque<nav_msgs::Odometry::ConstPtr> odom_;
  ros::WallTimer timer_;
  tf2_ros::TransformBroadcaster tf_;
  nav_msgs::Path path_;
  ros::Time last_tf_stamp_;
};

}  // namespace slam
}  // namespace scanstop

int main(int argc, char** argv) {
  ros::init(argc, argv, "icp_slam_node");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::slam::IcpSlamNode node(nh, pnh);
    // The ROS master gone: ERROR once; gone longer than master_timeout_s (or a new master): end
    // (the map directory is on disk after every scan: a restarted node reloads it).
    scanstop::RosMasterWatchdog watchdog("icp_slam_node", master_timeout_s);
    ros::spin();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("icp_slam_node: %s", e.what());
    // A start-up error (a map_dir that is a file, a bad parameter) repeats on every respawn: with
    // ~end_launch_on_setup_error the launch ends instead (issue 22).
    scanstop::endLaunchOnSetupError(pnh, "icp_slam_node");
    return 1;
  }
  return 0;
}
