#include "scanstop_sim/sim_node.h"

#include <nav_msgs/Odometry.h>
#include <rosgraph_msgs/Clock.h>
#include <scanstop_msgs/Progress.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/Marker.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <utility>
#include <vector>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_common/ros/robot_body.h"
#include "scanstop_sim/world_builder.h"

namespace scanstop {
namespace sim {
namespace {

nav_msgs::Odometry odometryMsg(const Pose2D& pose, const std::string& frame, const std::string& child,
                               const ros::Time& stamp) {
  nav_msgs::Odometry msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame;
  msg.child_frame_id = child;
  msg.pose.pose = ros_conv::toPoseMsg(pose);
  return msg;
}

}  // namespace

SimNode::SimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  ros_params::ParamReader params(pnh, "sim_node");
  params.known({"master_timeout_s", "end_launch_on_setup_error"});  // main()'s
  const std::string world_path = params.require<std::string>("world");
  WorldOptions world_options;
  bool allow_no_floor = false;
  params.optional("allow_no_floor", allow_no_floor);
  world_options.require_floor = !allow_no_floor;
  // Surface materials (issue #20): "" takes <world>.materials.yaml next to the STL when it exists.
  params.optional("materials_file", world_options.materials_file);

  std::string profile = "thesis";
  params.optional("error_profile", profile);
  SimConfig config;
  try {
    config.errors = makeProfile(profile);
  } catch (const ConfigError& e) {
    throw ConfigError("parameter '" + pnh.resolveName("error_profile") + "' = '" + profile + "': " + e.what());
  }
  int seed = 1;
  params.optional("seed", seed);
  if (seed < 0)
    throw ConfigError("parameter '" + pnh.resolveName("seed") + "' = " + std::to_string(seed) + " must be >= 0");
  config.seed = static_cast<uint64_t>(seed);
  // Every model field can be overridden by a parameter of the same name (config/sim.yaml).
  ScannerConfig& sc = config.scanner;
  params.optional("scanner/height_m", sc.height_m);
  params.optional("scanner/x_offset_m", sc.x_offset_m);
  params.optional("scanner/mount_offset_m", sc.mount_offset_m);
  params.optional("scanner/min_range_m", sc.min_range_m);
  params.optional("scanner/max_range_m", sc.max_range_m);
  params.optional("scanner/plane_time_s", sc.plane_time_s);
  params.optional("scanner/mixed_pixels", sc.mixed_pixels);
  params.optional("scanner/beam_divergence_rad", sc.beam_divergence_rad);
  params.optional("scanner/mixed_pixel_threshold_m", sc.mixed_pixel_threshold_m);
  params.optional("scanner/mixed_pixel_samples", sc.mixed_pixel_samples);
  // The selected profile's values from config/sim.yaml (profiles/<name>/sensor|motion/...). The
  // other profiles there are read too (into a scratch copy): their names are checked the same way.
  const auto read_profile = [&params](const std::string& pp, ErrorProfile& errors) {
    SensorNoiseConfig& sn = errors.sensor;
    params.optional(pp + "sensor/p_hit", sn.p_hit);
    params.optional(pp + "sensor/p_random", sn.p_random);
    params.optional(pp + "sensor/p_max", sn.p_max);
    params.optional(pp + "sensor/sigma_near_m", sn.sigma_near_m);
    params.optional(pp + "sensor/sigma_far_rel", sn.sigma_far_rel);
    params.optional(pp + "sensor/p_plane_loss", sn.p_plane_loss);
    MotionConfig& mo = errors.motion;
    params.optional(pp + "motion/curvature_per_m", mo.curvature_per_m);
    params.optional(pp + "motion/curvature_sigma_per_m", mo.curvature_sigma_per_m);
    params.optional(pp + "motion/distance_error_rel", mo.distance_error_rel);
    params.optional(pp + "motion/distance_sigma_rel", mo.distance_sigma_rel);
    params.optional(pp + "motion/finish_angle_rad", mo.finish_angle_rad);
    params.optional(pp + "motion/finish_angle_sigma_rad", mo.finish_angle_sigma_rad);
    params.optional(pp + "motion/rotation_error_rel", mo.rotation_error_rel);
    params.optional(pp + "motion/rotation_sigma_rel", mo.rotation_sigma_rel);
    params.optional(pp + "motion/rotation_position_sigma_m_per_rad", mo.rotation_position_sigma_m_per_rad);
  };
  const std::string pp = "profiles/" + profile + "/";
  XmlRpc::XmlRpcValue profiles;
  if (pnh.getParam("profiles", profiles) && profiles.getType() == XmlRpc::XmlRpcValue::TypeStruct)
    for (auto it = profiles.begin(); it != profiles.end(); ++it)
      if (it->first != profile) {
        ErrorProfile scratch;
        read_profile("profiles/" + it->first + "/", scratch);
      }
  read_profile(pp, config.errors);
  MotionConfig& mo = config.errors.motion;
  params.optional("motion/linear_speed_mps", mo.linear_speed_mps);
  params.optional("motion/angular_speed_radps", mo.angular_speed_radps);
  // The body (robot_body/..., config/robot_body.yaml): the collision disc and the height up to
  // which the world's geometry blocks it. ~robot_radius overrides the disc (a WARN names both).
  const RobotBody body = ros_params::readRobotBody(nh);
  config.robot_radius_m = body.radius_m;
  world_options.obstacle_max_z_m = body.height_m;
  if (params.has("robot_radius_m")) {
    params.optional("robot_radius_m", config.robot_radius_m);
    ROS_WARN("sim_node: %s = %.3f m overrides the robot body's radius %.3f m (config/robot_body.yaml)",
             pnh.resolveName("robot_radius_m").c_str(), config.robot_radius_m, body.radius_m);
  }
  params.optional("max_forward_m", config.max_forward_m);
  params.optional("max_rotate_rad", config.max_rotate_rad);
  params.optional("outlier_filter", config.outlier_filter);
  try {
    config.validate(pp);
  } catch (const ConfigError& e) {
    throw ConfigError(std::string(e.what()) + " (private namespace " + pnh.getNamespace() + ")");
  }
  params.optional("motion_time_scale", motion_time_scale_);
  if (!(motion_time_scale_ >= 0.0 && motion_time_scale_ <= 10.0))
    throw ConfigError("parameter '" + pnh.resolveName("motion_time_scale") +
                      "' = " + std::to_string(motion_time_scale_) + " is out of range [0, 10]");
  params.optional("scan_time_scale", scan_time_scale_);
  if (!(scan_time_scale_ >= 0.0 && scan_time_scale_ <= 10.0))
    throw ConfigError("parameter '" + pnh.resolveName("scan_time_scale") + "' = " + std::to_string(scan_time_scale_) +
                      " is out of range [0, 10]");
  // rviz's view of the world from above: the ceiling would hide the room (display only).
  params.optional("world_display_max_z_m", world_display_max_z_m_, 0.1, 1000.0, "m");

  std::string start_text;
  params.optional("start_pose", start_text);

  params.optional("world_frame", world_frame_);
  params.optional("map_frame", map_frame_);
  params.optional("odom_frame", odom_frame_);
  params.optional("base_frame", base_frame_);
  params.optional("laser_frame", laser_frame_);
  params.optional("odom_as_map", odom_as_map_);
  params.frames({{"world_frame", world_frame_},
                 {"map_frame", map_frame_},
                 {"odom_frame", odom_frame_},
                 {"base_frame", base_frame_},
                 {"laser_frame", laser_frame_}});
  nh.param("/use_sim_time", publish_clock_, false);
  params.known({"state_file"});  // read below, once the world is loaded
  params.rejectUnknown();        // before the world is loaded: a typo ends the node at once

  ROS_INFO("sim_node: loading world %s", world_path.c_str());
  // The world file first, then the start pose: the error names the right one (issue 22).
  Pose2D start;
  try {
    sim_ = makeSimulator(world_path, world_options, config, start_text, pnh.resolveName("start_pose"), &start);
  } catch (const MaterialsError& e) {
    throw ConfigError("parameter '" + pnh.resolveName("materials_file") + "' = '" + world_options.materials_file + "'" +
                      (world_options.materials_file.empty() ? " (the world's own materials file)" : "") + ": " +
                      e.what());
  } catch (const IoError& e) {
    throw ConfigError("parameter '" + pnh.resolveName("world") + "': " + e.what());
  } catch (const std::invalid_argument& e) {
    throw ConfigError(std::string("parameter '") + pnh.resolveName("start_pose") + "': " + e.what());
  }
  ROS_INFO("sim_node: %s (%zu triangles, %zu floor), start %s, profile %s, seed %d", world_path.c_str(),
           sim_->world().mesh().faces.size(), sim_->world().floorTriangles(), start.toString().c_str(), profile.c_str(),
           seed);
  const MaterialMap& materials = sim_->world().materials();
  const std::vector<size_t> region_triangles = sim_->world().regionCounts();
  for (size_t r = 0; r < materials.regions.size(); ++r) {
    const MaterialRegion& m = materials.regions[r];
    if (region_triangles[r] == 0)
      ROS_WARN("sim_node: materials %s: region '%s' (%s) contains no triangle's centroid", materials.source.c_str(),
               m.name.c_str(), materialName(m.material));
    else
      ROS_INFO("sim_node: materials %s: region '%s': %zu triangles %s", materials.source.c_str(), m.name.c_str(),
               region_triangles[r], materialName(m.material));
  }
  if (sc.mixed_pixels)
    ROS_INFO("sim_node: mixed pixels on (footprint %.5f rad, %dx%d sub-rays, depth step %.3f m)",
             sc.beam_divergence_rad, sc.mixed_pixel_samples, sc.mixed_pixel_samples, sc.mixed_pixel_threshold_m);
  // A restarted sim_node continues the simulation of the one that died (pose, odometry, clock,
  // random sequence): a real robot does not teleport back to its start when its driver restarts.
  params.optional("state_file", state_file_);
  if (!state_file_.empty() && std::ifstream(state_file_).good()) {
    try {
      sim_->restoreState(readFile(state_file_));
      ROS_INFO("sim_node: resumed the simulation from %s: robot at %s (world), odometry %s, clock %.1f s",
               state_file_.c_str(), sim_->trueInWorld().toString().c_str(), sim_->odometry().toString().c_str(),
               sim_->clock());
    } catch (const StateOfAnotherWorld& e) {
      // Another world's simulation: overwriting it would lose that run's robot pose; the run
      // directory belongs to something else (issue 22).
      throw ConfigError("parameter '" + pnh.resolveName("state_file") + "' = '" + state_file_ + "': " + e.what() +
                        ": the run directory belongs to another run; use a new run_dir or delete this one");
    } catch (const std::exception& e) {
      ROS_ERROR("sim_node: ignoring the state file %s (%s): starting at the start pose", state_file_.c_str(), e.what());
    }
  }

  if (publish_clock_) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  odom_pub_ = nh.advertise<nav_msgs::Odometry>("odom", 10, true);
  tf_connect_pub_ = nh.advertise<tf2_msgs::TFMessage>(
      "/tf", 100, [this](const ros::SingleSubscriberPublisher& pub) { onTfSubscriber(pub); });
  truth_pub_ = nh.advertise<nav_msgs::Odometry>("ground_truth", 10, true);
  clearance_pub_ = nh.advertise<scanstop_msgs::MotionClearance>("ground_truth/clearance", 100);
  scan_pub_ = nh.advertise<sensor_msgs::PointCloud2>("scanner/last_scan", 1, true);
  progress_pub_ = nh.advertise<scanstop_msgs::Progress>("scanner/progress", 10);
  marker_pub_ = nh.advertise<visualization_msgs::Marker>("sim/world_mesh", 1, true);
  take_scan_srv_ = nh.advertiseService("scanner/take_scan", &SimNode::onTakeScan, this);
  rotate_srv_ = nh.advertiseService("base/rotate", &SimNode::onRotate, this);
  forward_srv_ = nh.advertiseService("base/forward", &SimNode::onForward, this);
  reset_srv_ = nh.advertiseService("sim/reset", &SimNode::onReset, this);
  hidden_obstacle_srv_ = nh.advertiseService("sim/add_hidden_obstacle", &SimNode::onAddHiddenObstacle, this);
  clock_timer_ = nh.createWallTimer(ros::WallDuration(0.1), &SimNode::onClockTimer, this);
  // Nothing is saved until the simulation changes (a motion, a scan, a reset): a sim_node started on a
  // run directory that turns out to be another run's (the mission refuses it) leaves no file there.
  publishState(false);
  publishStaticTransforms();
  publishWorldMarker();
}

ros::Time SimNode::now() const {
  if (publish_clock_) return ros::Time(clock_start_s_ + sim_->clock());
  return ros::Time::now();
}

void SimNode::onClockTimer(const ros::WallTimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!publish_clock_) return;
  rosgraph_msgs::Clock clock;
  clock.clock = now();
  clock_pub_.publish(clock);
}

void SimNode::persistState() {
  if (state_file_.empty()) return;
  try {
    writeFileAtomic(state_file_, sim_->saveState());
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(10.0, "sim_node: cannot save the simulation state: %s", e.what());
  }
}

void SimNode::publishState(bool persist) {
  if (persist) persistState();
  const ros::Time stamp = now();
  if (publish_clock_) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
  }
  odom_pub_.publish(odometryMsg(sim_->odometry(), odom_frame_, base_frame_, stamp));
  truth_pub_.publish(odometryMsg(sim_->trueInMap(), map_frame_, base_frame_ + "_truth", stamp));
  const geometry_msgs::TransformStamped odom_tf =
      ros_conv::toTransformMsg(sim_->odometry(), odom_frame_, base_frame_, stamp);
  {
    std::lock_guard<std::mutex> lock(tf_mutex_);
    while (!recent_odom_tf_.empty() && recent_odom_tf_.back().header.stamp >= odom_tf.header.stamp)
      recent_odom_tf_.pop_back();  // same stamp (no time passed) or a reset clock: the newest wins
    recent_odom_tf_.push_back(odom_tf);
    while (recent_odom_tf_.size() > kRecentTf) recent_odom_tf_.pop_front();
  }
  tf_.sendTransform(odom_tf);
}

void SimNode::onTfSubscriber(const ros::SingleSubscriberPublisher& pub) {
  tf2_msgs::TFMessage msg;
  {
    std::lock_guard<std::mutex> lock(tf_mutex_);
    if (recent_odom_tf_.empty()) return;
    msg.transforms.assign(recent_odom_tf_.begin(), recent_odom_tf_.end());
  }
  pub.publish(msg);
}

void SimNode::publishStaticTransforms() {
  const ros::Time stamp = now();
  Eigen::Isometry3d T_base_laser = Eigen::Isometry3d::Identity();
  T_base_laser.translation() = Eigen::Vector3d(sim_->config().scanner.x_offset_m, 0.0, sim_->config().scanner.height_m);
  std::vector<geometry_msgs::TransformStamped> transforms{
      ros_conv::toTransformMsg(sim_->start(), world_frame_, map_frame_, stamp),
      ros_conv::toTransformMsg(T_base_laser, base_frame_, laser_frame_, stamp)};
  // Without a SLAM node, odometry is the only estimate: map -> odom is the identity.
  if (odom_as_map_) transforms.push_back(ros_conv::toTransformMsg(Pose2D(), map_frame_, odom_frame_, stamp));
  static_tf_.sendTransform(transforms);
}

void SimNode::publishWorldMarker() {
  visualization_msgs::Marker m;
  m.header.frame_id = world_frame_;
  m.header.stamp = now();
  m.ns = "world";
  m.type = visualization_msgs::Marker::TRIANGLE_LIST;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 1.0;
  m.color.r = m.color.g = m.color.b = 0.7f;
  m.color.a = 0.35f;
  const TriangleMesh& mesh = sim_->world().mesh();
  m.points.reserve(mesh.faces.size() * 3);
  for (const auto& f : mesh.faces) {
    // The ceiling (a triangle wholly above world_display_max_z_m) is left out: it hides the room.
    if (mesh.vertices[f[0]].z() > world_display_max_z_m_ && mesh.vertices[f[1]].z() > world_display_max_z_m_ &&
        mesh.vertices[f[2]].z() > world_display_max_z_m_)
      continue;
    for (int k = 0; k < 3; ++k) {
      geometry_msgs::Point p;
      p.x = mesh.vertices[f[k]].x();
      p.y = mesh.vertices[f[k]].y();
      p.z = mesh.vertices[f[k]].z();
      m.points.push_back(p);
    }
  }
  marker_pub_.publish(m);
}

bool SimNode::onTakeScan(scanstop_msgs::TakeScan::Request& req, scanstop_msgs::TakeScan::Response& res) {
  res.success = false;
  res.message = checkScanPlanes(req.planes);
  if (!res.message.empty()) return true;
  // A scan needs the robot standing still (thesis 3.2): refused, not queued, while the base moves.
  if (moving_) {
    res.message = "the base is moving (a rotate/forward motion is running): a scan needs the robot standing still";
    return true;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (moving_) {
    res.message = "the base is moving (a rotate/forward motion is running): a scan needs the robot standing still";
    return true;
  }
  scanstop_msgs::Progress progress;
  progress.header.stamp = now();
  progress.step = "take_scan";
  progress.total = req.planes;
  progress.message = "scanning " + std::to_string(req.planes) + " planes";
  progress_pub_.publish(progress);

  const ScanOutput scan = sim_->scan(req.planes);
  // With scan_time_scale > 0 the scan takes that share of its modelled time on the wall clock; the
  // state is persisted after it, so a sim_node killed meanwhile takes the same scan again.
  if (scan_time_scale_ > 0.0) ros::WallDuration(scan.duration_s * scan_time_scale_).sleep();
  const ros::Time stamp = now();
  res.cloud = ros_conv::toMsg(scan.cloud, base_frame_, stamp);
  res.odom_pose = ros_conv::toPoseStamped(sim_->odometry(), odom_frame_, stamp);
  res.counts.raw_points = scan.raw_points;
  res.counts.valid_points = scan.valid_points;
  res.counts.planes_dropped = scan.planes_dropped;
  res.counts.outliers_removed = scan.outliers_removed;
  res.duration_s = scan.duration_s;
  res.success = true;
  publishState();
  scan_pub_.publish(res.cloud);
  progress.header.stamp = stamp;
  progress.done = req.planes;
  progress.message = std::to_string(scan.valid_points) + " valid points, " + std::to_string(scan.planes_dropped) +
                     " planes dropped, " + std::to_string(scan.outliers_removed) + " outliers removed";
  progress_pub_.publish(progress);
  return true;
}

bool SimNode::onRotate(scanstop_msgs::Rotate::Request& req, scanstop_msgs::Rotate::Response& res) {
  res.success = false;
  res.message = checkRotation(req.angle_rad, sim_->config().max_rotate_rad);
  if (!res.message.empty()) return true;
  const MotionOutput out = runMotion([&] { return sim_->rotate(req.angle_rad); }, 0.0, req.angle_rad, &res.message);
  if (!res.message.empty()) return true;
  publishClearance("rotate", req.angle_rad, out);
  res.achieved_angle_rad = out.achieved;
  res.collision = out.collision;
  res.duration_s = out.duration_s;
  res.success = !out.collision;
  std::lock_guard<std::mutex> lock(mutex_);
  res.odom_pose = ros_conv::toPoseStamped(sim_->odometry(), odom_frame_, now());
  return true;
}

bool SimNode::onForward(scanstop_msgs::Forward::Request& req, scanstop_msgs::Forward::Response& res) {
  res.success = false;
  res.message = checkForward(req.distance_m, sim_->config().max_forward_m);
  if (!res.message.empty()) return true;
  const MotionOutput out = runMotion(
      [&] {
        placeArmedObstacle(req.distance_m);
        return sim_->forward(req.distance_m);
      },
      req.distance_m, 0.0, &res.message);
  if (!res.message.empty()) return true;
  publishClearance("forward", req.distance_m, out);
  res.achieved_distance_m = out.achieved;
  res.collision = out.collision;
  res.duration_s = out.duration_s;
  res.success = !out.collision;
  if (out.collision)
    res.message = "collision after " + std::to_string(out.achieved) + " m: the robot touched an obstacle";
  std::lock_guard<std::mutex> lock(mutex_);
  res.odom_pose = ros_conv::toPoseStamped(sim_->odometry(), odom_frame_, now());
  return true;
}

void SimNode::publishClearance(const char* motion, double command, const MotionOutput& out) {
  scanstop_msgs::MotionClearance m;
  m.header.stamp = now();
  m.header.frame_id = map_frame_;
  m.motion_index = motion_index_++;
  m.motion = motion;
  m.command = command;
  m.min_clearance_m = out.min_clearance_m;
  m.collision = out.collision;
  clearance_pub_.publish(m);
}

void SimNode::onMasterLost(const std::string& why) {
  ROS_ERROR("sim_node: refusing motions until the ROS master is back");
  std::lock_guard<std::mutex> lock(master_mutex_);
  master_lost_ = why;
}

void SimNode::onMasterBack() {
  ROS_WARN("sim_node: the ROS master is back: motions accepted again");
  std::lock_guard<std::mutex> lock(master_mutex_);
  master_lost_.clear();
}

MotionOutput SimNode::runMotion(const std::function<MotionOutput()>& motion, double distance_m, double angle_rad,
                                std::string* refused) {
  {
    std::lock_guard<std::mutex> lock(master_mutex_);
    if (!master_lost_.empty()) {
      *refused = "refused: " + master_lost_;
      return MotionOutput();
    }
  }
  if (moving_.exchange(true)) {
    *refused = "another rotate/forward motion is running";
    return MotionOutput();
  }
  MotionOutput out;
  Pose2D before;
  try {
    std::lock_guard<std::mutex> lock(mutex_);
    before = sim_->odometry();
    out = motion();
  } catch (const std::exception& e) {  // checked before; the simulator refuses the same cases
    moving_ = false;
    *refused = e.what();
    return out;
  }
  if (motion_time_scale_ > 0.0 && out.duration_s > 0.0) {
    // The motion takes its modelled time on the wall clock: odom shows the robot moving (the twist
    // of the commanded motion at the start pose) until it arrives.
    const double speed = distance_m != 0.0 ? sim_->config().errors.motion.linear_speed_mps
                                           : sim_->config().errors.motion.angular_speed_radps;
    nav_msgs::Odometry moving = odometryMsg(before, odom_frame_, base_frame_, ros::Time::now());
    {
      std::lock_guard<std::mutex> lock(mutex_);
      moving.header.stamp = now();
    }
    moving.twist.twist.linear.x = distance_m > 0 ? speed : distance_m < 0 ? -speed : 0.0;
    moving.twist.twist.angular.z = angle_rad > 0 ? speed : angle_rad < 0 ? -speed : 0.0;
    odom_pub_.publish(moving);
    ros::WallDuration(out.duration_s * motion_time_scale_).sleep();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    publishState();
  }
  moving_ = false;
  return out;
}

bool SimNode::onReset(scanstop_msgs::ResetSim::Request& req, scanstop_msgs::ResetSim::Response& res) {
  if (moving_) {
    res.success = false;
    res.message = "the base is moving (a rotate/forward motion is running): reset after it";
    return true;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    sim_->reset(Pose2D(req.pose.x, req.pose.y, req.pose.theta), req.seed);
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    return true;
  }
  res.success = true;
  publishState();
  publishStaticTransforms();
  return true;
}

void SimNode::placeArmedObstacle(double distance_m) {
  if (!armed_obstacle_) return;
  const Simulator::HiddenObstacle& a = *armed_obstacle_;
  if (std::abs(distance_m) < a.x - a.radius - sim_->config().robot_radius_m + 0.05)
    return;  // this motion would not reach it
  // In the motion's frame: ahead of the robot on a forward motion, behind it on a backward one.
  const double way = distance_m < 0.0 ? -1.0 : 1.0;
  const Pose2D w = sim_->trueInWorld() * Pose2D(way * a.x, way * a.y, 0.0);
  try {
    sim_->addHiddenObstacle({w.x, w.y, a.radius});
    ROS_WARN(
        "sim_node: hidden obstacle at (%.3f, %.3f) m in %s, radius %.3f m, %.2f m %s the robot in its way (the "
        "laser does not see it)",
        w.x, w.y, world_frame_.c_str(), a.radius, a.x, way < 0.0 ? "behind" : "ahead of");
  } catch (const std::exception& e) {
    ROS_WARN("sim_node: the armed hidden obstacle was not placed: %s", e.what());
  }
  armed_obstacle_.reset();
}

bool SimNode::onAddHiddenObstacle(scanstop_msgs::AddHiddenObstacle::Request& req,
                                  scanstop_msgs::AddHiddenObstacle::Response& res) {
  res.success = false;
  if (moving_) {
    res.message = "the base is moving (a rotate/forward motion is running): add the obstacle after it";
    return true;
  }
  const std::string frame = req.frame_id.empty() ? world_frame_ : req.frame_id;
  if (frame != world_frame_ && frame != map_frame_) {
    res.message = "frame_id '" + req.frame_id + "' is neither '" + world_frame_ + "' nor '" + map_frame_ + "'";
    return true;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  Simulator::HiddenObstacle h;
  h.radius = req.radius;
  if (req.on_next_forward) {
    if (!std::isfinite(req.x) || !std::isfinite(req.y) || !(req.x > 0.0) || !(req.radius > 0.0 && req.radius <= 2.0)) {
      res.message = "on_next_forward needs a finite x > 0 m ahead and a radius in (0, 2] m";
      return true;
    }
    armed_obstacle_ = Simulator::HiddenObstacle{req.x, req.y, req.radius};
    res.success = true;
    res.message = "armed: a hidden obstacle appears " + std::to_string(req.x) +
                  " m along the way of the next straight motion that reaches it (ahead, or behind on a backward one)";
    ROS_WARN("sim_node: %s", res.message.c_str());
    return true;
  }
  if (frame == map_frame_) {
    const Pose2D w = sim_->start() * Pose2D(req.x, req.y, 0.0);
    h.x = w.x;
    h.y = w.y;
  } else {
    h.x = req.x;
    h.y = req.y;
  }
  try {
    sim_->addHiddenObstacle(h);
  } catch (const std::exception& e) {
    res.message = e.what();
    return true;
  }
  res.success = true;
  char text[160];
  std::snprintf(text, sizeof(text), "hidden obstacle at (%.3f, %.3f) m in %s, radius %.3f m", h.x, h.y,
                world_frame_.c_str(), h.radius);
  res.message = text;
  ROS_WARN("sim_node: %s (the laser does not see it)", text);
  publishState();
  return true;
}

}  // namespace sim
}  // namespace scanstop
