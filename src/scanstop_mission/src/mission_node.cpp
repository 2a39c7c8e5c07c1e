#include "scanstop_mission/mission_node.h"

#include <dirent.h>
#include <malloc.h>
#include <scanstop_msgs/MissionStatus.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/launch_control.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_common/ros/robot_body.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_eval/ground_truth.h"
#include "scanstop_eval/surface_accuracy.h"
#include "scanstop_eval/surface_coverage.h"
#include "scanstop_mission/report.h"
#include "scanstop_mission/run_directory.h"

namespace scanstop {
namespace mission {
namespace {

/// PNG files below run_dir/<sub> (sorted), relative to run_dir: the explorer's per-step figures.
std::vector<std::string> listImages(const std::string& run_dir, const std::string& sub) {
  std::vector<std::string> out;
  if (DIR* d = opendir((run_dir + "/" + sub).c_str())) {
    while (const dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".png") == 0) out.push_back(sub + "/" + name);
    }
    closedir(d);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// "corridor" for "/a/b/corridor.stl".
std::string fileStem(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  const size_t dot = name.rfind('.');
  return dot == std::string::npos ? name : name.substr(0, dot);
}

/// ~run_identity (a map of field: value, any scalar type) as text fields.
std::map<std::string, std::string> readIdentityParam(const ros::NodeHandle& pnh) {
  std::map<std::string, std::string> out;
  XmlRpc::XmlRpcValue v;
  if (!pnh.getParam("run_identity", v)) return out;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    throw ConfigError("parameter '" + pnh.resolveName("run_identity") + "' must be a map of field: value");
  for (auto it = v.begin(); it != v.end(); ++it) {
    XmlRpc::XmlRpcValue& x = it->second;
    std::ostringstream text;
    switch (x.getType()) {
      case XmlRpc::XmlRpcValue::TypeString:
        text << static_cast<std::string&>(x);
        break;
      case XmlRpc::XmlRpcValue::TypeInt:
        text << static_cast<int>(x);
        break;
      case XmlRpc::XmlRpcValue::TypeDouble:
        text << static_cast<double>(x);
        break;
      case XmlRpc::XmlRpcValue::TypeBoolean:
        text << (static_cast<bool>(x) ? "true" : "false");
        break;
      default:
        throw ConfigError("parameter '" + pnh.resolveName("run_identity/" + it->first) + "' must be a scalar");
    }
    out[it->first] = text.str();
  }
  return out;
}

}  // namespace

MissionNode::MissionNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  ros_params::ParamReader params(pnh, "mission_node");
  config_.run_dir = params.require<std::string>("run_dir");
  params.optional("planes", config_.planes);
  params.optional("max_scans", config_.max_scans);
  params.optional("waypoint_tolerance_m", config_.waypoint_tolerance_m);
  params.optional("heading_tolerance_rad", config_.heading_tolerance_rad);
  params.optional("min_scan_travel_m", config_.min_scan_travel_m);
  params.optional("scan_on_the_way", config_.scan_on_the_way);
  params.optional("scan_error_bound_m", config_.scan_error_bound_m);
  params.optional("return_home", config_.return_home);
  params.optional("home_tolerance_m", config_.home_tolerance_m);
  params.optional("home_scan_travel_m", config_.home_scan_travel_m);
  params.optional("max_step_retries", config_.max_step_retries);
  params.optional("contact_backoff_m", config_.contact_backoff_m);
  params.optional("contact_offset_m", config_.contact_offset_m);
  params.optional("max_contacts", config_.max_contacts);
  params.optional("contact_point_radius_m", config_.contact_point_radius_m);
  params.optional("leg_check", config_.leg_check);
  // The swept disc and the heights of the leg check come from the body (robot_body/...,
  // config/robot_body.yaml): radius + leg_check_body_margin, up to the body's height.
  // ~leg_check_radius / ~leg_check_max_z set explicitly override them.
  {
    const RobotBody body = ros_params::readRobotBody(pnh);
    double body_margin = 0.02;
    params.optional("leg_check_body_margin_m", body_margin);
    if (!(body_margin >= 0.0 && body_margin <= 1.0))
      throw ConfigError("parameter '" + pnh.resolveName("leg_check_body_margin_m") +
                        "' = " + std::to_string(body_margin) + " m must be in [0, 1] m");
    config_.leg_check_radius_m = body.radius_m + body_margin;
    config_.leg_check_max_z_m = body.height_m;
  }
  params.optional("leg_check_radius_m", config_.leg_check_radius_m);
  params.optional("leg_check_margin_m", config_.leg_check_margin_m);
  params.optional("obstruction_standoff_m", config_.obstruction_standoff_m);
  params.optional("leg_check_min_z_m", config_.leg_check_min_z_m);
  params.optional("leg_check_max_z_m", config_.leg_check_max_z_m);
  params.optional("leg_check_self_m", config_.leg_check_self_m);
  params.optional("leg_check_min_points", config_.leg_check_min_points);
  params.optional("leg_check_turn_error", config_.leg_check_turn_error);
  params.optional("leg_check_drift", config_.leg_check_drift);
  params.optional("leg_check_distance_error", config_.leg_check_distance_error);
  params.optional("leg_check_turn_position_m_per_rad", config_.leg_check_turn_position_m_per_rad);
  params.optional("reverse_legs", config_.reverse_legs);
  params.optional("relocalize_min_travel_m", config_.relocalize_min_travel_m);
  params.optional("relocalize_min_turn_rad", config_.relocalize_min_turn_rad);
  params.optional("relocalize_as_target_m", config_.relocalize_as_target_m);
  params.optional("relocalize_planes", config_.relocalize_planes);
  params.optional("leg_sidestep_m", config_.leg_sidestep_m);
  params.optional("retry_backoff_s", config_.retry_backoff_s);
  params.optional("max_consecutive_failed_cycles", config_.max_consecutive_failed_cycles);
  params.optional("build_mesh", config_.build_mesh);
  params.optional("world", config_.world);
  config_.mesh_output = config_.run_dir + "/mesh.ply";
  params.optional("mesh_output", config_.mesh_output);
  std::string map_dir = config_.run_dir + "/map";
  params.optional("map_dir", map_dir);
  map_dir_ = map_dir;
  params.optional("world_file", world_file_);
  params.optional("world_frame", world_frame_);
  params.optional("map_frame", map_frame_);
  robot_radius_given_ = params.has("robot_radius_m");
  params.optional("robot_radius_m", robot_radius_m_);
  explorer_config_ = config_.run_dir + "/explorer/config.yaml";
  params.optional("explorer_config", explorer_config_);
  params.optional("wait_for_recorder_s", wait_for_recorder_s_);
  if (!(wait_for_recorder_s_ >= 0.0 && wait_for_recorder_s_ <= 600.0))
    throw ConfigError("parameter '" + pnh.resolveName("wait_for_recorder_s") +
                      "' = " + std::to_string(wait_for_recorder_s_) + " is outside [0, 600] s");
  params.optional("surface_planes", surface_planes_);
  if (surface_planes_ < 0 || surface_planes_ > 2000)
    throw ConfigError("parameter '" + pnh.resolveName("surface_planes") + "' = " + std::to_string(surface_planes_) +
                      " must be in [0, 2000] (0: no surface coverage)");
  if (!(robot_radius_m_ > 0.0 && robot_radius_m_ <= 5.0))
    throw ConfigError("parameter '" + pnh.resolveName("robot_radius_m") + "' = " + std::to_string(robot_radius_m_) +
                      " m must be in (0, 5] m");
  if (!world_file_.empty() && (world_frame_.empty() || map_frame_.empty() || world_frame_ == map_frame_))
    throw ConfigError("parameters '" + pnh.resolveName("world_frame") + "' and '" + pnh.resolveName("map_frame") +
                      "' must be two different, non-empty frame ids");
  CallTimeouts timeouts;
  params.optional("wait_for_service_timeout_s", timeouts.wait_for_service_timeout_s);
  params.optional("scan_timeout_s", timeouts.scan_timeout_s);
  params.optional("motion_timeout_s", timeouts.motion_timeout_s);
  params.optional("register_timeout_s", timeouts.register_timeout_s);
  params.optional("plan_timeout_s", timeouts.plan_timeout_s);
  params.optional("mesh_timeout_s", timeouts.mesh_timeout_s);
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"wait_for_service_timeout_s", timeouts.wait_for_service_timeout_s},
        {"scan_timeout_s", timeouts.scan_timeout_s},
        {"motion_timeout_s", timeouts.motion_timeout_s},
        {"register_timeout_s", timeouts.register_timeout_s},
        {"plan_timeout_s", timeouts.plan_timeout_s},
        {"mesh_timeout_s", timeouts.mesh_timeout_s}}) {
    if (!(value > 0.0 && value < 1e6))
      throw ConfigError(std::string("parameter '") + pnh.resolveName(name) + "' = " + std::to_string(value) +
                        " must be in (0, 1e6) s");
  }
  bool autostart = true;
  params.optional("autostart", autostart);
  params.optional("shutdown_when_done", shutdown_when_done_);
  params.optional("html_report", html_report_);
  params.optional("report_script", report_script_);
  if (html_report_ && report_script_.empty()) {
    // catkin_install_python puts make_report.py beside mission_node (devel and install space).
    char exe[4096];
    const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    const std::string self = n > 0 ? std::string(exe, static_cast<size_t>(n)) : std::string();
    report_script_ = self.substr(0, self.find_last_of('/') + 1) + "make_report.py";
  }
  params.optional("master_timeout_s", master_timeout_s_);
  // run_identity: readIdentityParam() below; robot_body/...: readRobotBody() (when set in this namespace).
  params.known({"run_identity", "robot_body"});
  // A misspelt parameter would silently keep its default: refuse it.
  params.rejectUnknown();
  try {
    config_.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(std::string(e.what()) + " (in " + pnh.getNamespace() + ")");
  }
  if (map_dir.empty()) throw ConfigError("parameter '" + pnh.resolveName("map_dir") + "' is empty");

  // The world actually simulated is the world file (sim_node loads it): the report names that one.
  if (!world_file_.empty()) {
    const std::string used = fileStem(world_file_);
    if (!config_.world.empty() && config_.world != used)
      ROS_WARN("mission: parameter '%s' = '%s' but the world file is %s: the report names '%s'",
               pnh.resolveName("world").c_str(), config_.world.c_str(), world_file_.c_str(), used.c_str());
    config_.world = used;
  }
  // The run directory before anything is written into it: a directory that is not one, or that holds
  // another run's mission, ends the node here (required in the launch: the launch ends with it).
  RunIdentity identity;
  identity.fields = readIdentityParam(pnh);
  identity.fields["world"] = config_.world;
  identity.fields["planes"] = std::to_string(config_.planes);
  if (!world_file_.empty()) {
    try {
      identity.fields["world_file_fnv1a64"] = fileFingerprint(world_file_);
    } catch (const IoError& e) {
      throw ConfigError("parameter '" + pnh.resolveName("world_file") + "' = '" + world_file_ +
                        "': the world file: " + e.problem());
    }
  }
  const RunDirectory run_directory(config_.run_dir, identity);
  ROS_INFO("mission: run directory %s (%s; identity in %s)", run_directory.path().c_str(),
           run_directory.created()   ? "new"
           : run_directory.resumed() ? "resuming its mission"
                                     : "no mission in it yet",
           run_directory.identityPath().c_str());
  if (!run_directory.setAside().empty())
    ROS_WARN(
        "mission: the run directory held a mission that ended before its first scan: starting afresh (its "
        "state kept as %s)",
        run_directory.setAside().c_str());

  robot_ = std::make_unique<RosRobotSystem>(nh_, timeouts, map_dir);
  mission_ = std::make_unique<Mission>(
      config_, *robot_, [](const std::string& s) { ROS_INFO_STREAM("mission: " << s); },
      [](const std::string& s) { ROS_WARN_STREAM("mission: " << s); });
  if (mission_->loadSavedState())
    ROS_INFO("mission: resuming the mission saved in %s (%zu scans so far)", mission_->statePath().c_str(),
             mission_->snapshot().scans.size());

  status_pub_ = nh_.advertise<scanstop_msgs::MissionStatus>("mission/status", 10, true);
  // tf2's static transforms are on the global /tf_static (latched), as every tf2 listener reads them.
  if (!world_file_.empty()) static_tf_sub_ = nh_.subscribe("/tf_static", 10, &MissionNode::onStaticTf, this);
  mission_->setStateListener([this] {
    ros::WallTimerEvent none;
    publishStatus(none);
  });
  start_srv_ = nh_.advertiseService("mission/start", &MissionNode::onStart, this);
  pause_srv_ = nh_.advertiseService("mission/pause", &MissionNode::onPause, this);
  resume_srv_ = nh_.advertiseService("mission/resume", &MissionNode::onResume, this);
  abort_srv_ = nh_.advertiseService("mission/abort", &MissionNode::onAbort, this);
  status_timer_ = nh_.createWallTimer(ros::WallDuration(1.0), &MissionNode::publishStatus, this);
  if (autostart) {
    running_ = true;
    runner_ = std::thread(&MissionNode::runMission, this);
  } else {
    ROS_INFO("mission: ready; call mission/start to begin");
  }
}

MissionNode::~MissionNode() {
  if (mission_) mission_->abort();
  if (runner_.joinable()) runner_.join();
}

void MissionNode::onStaticTf(const tf2_msgs::TFMessage::ConstPtr& msg) {
  for (const auto& t : msg->transforms)
    if (t.header.frame_id == world_frame_ && t.child_frame_id == map_frame_) {
      const auto& q = t.transform.rotation;
      const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
      std::lock_guard<std::mutex> lock(start_mutex_);
      world_T_map_ = Pose2D(t.transform.translation.x, t.transform.translation.y, yaw);
    }
}

std::optional<TrueCoverage> MissionNode::trueCoverage(const std::string& mesh_file) {
  if (world_file_.empty()) return std::nullopt;
  std::optional<Pose2D> start;
  {
    std::lock_guard<std::mutex> lock(start_mutex_);
    start = world_T_map_;
  }
  if (!start) {
    ROS_WARN("mission: no %s -> %s transform on /tf_static (sim_node publishes it): no true coverage",
             world_frame_.c_str(), map_frame_.c_str());
    return std::nullopt;
  }
  // The floor map as the explorer of this run built it: with the configuration explorer_node wrote
  // into its run directory (explorer_config), the robot radius from there unless ~robot_radius is set.
  try {
    const TriangleMesh world = readStl(world_file_);
    const MapDirectory map(map_dir_);
    std::string note;
    const eval::GroundTruthCoverage c = eval::groundTruthCoverageOfRun(
        world, *start, map, explorer_config_,
        robot_radius_given_ ? std::optional<double>(robot_radius_m_) : std::nullopt, &note);
    if (!note.empty()) ROS_WARN("mission: true coverage: %s", note.c_str());
    const double robot_radius = c.robot_radius_m;
    TrueCoverage truth{c.coverage, c.reachable_m2, std::nullopt, 0, std::nullopt};
    if (surface_planes_ > 0) surfaceCoverage(world, *start, map, robot_radius, mesh_file, truth);
    return truth;
  } catch (const std::exception& e) {
    ROS_WARN("mission: no true coverage (%s: %s)", world_file_.c_str(), e.what());
    return std::nullopt;
  }
}

void MissionNode::surfaceCoverage(const TriangleMesh& world, const Pose2D& start, const MapDirectory& map,
                                  double robot_radius, const std::string& mesh_file, TrueCoverage& truth) {
  // The surface visible from the truly reachable floor: the coverage oracle's candidate scans
  // (perfect, surface_planes planes, every 0.5 m), then the map's points within 3 cm of it.
  try {
    const eval::RunSurfaceCoverage run =
        eval::surfaceCoverageOfRun(world, fileStem(world_file_), start, map, robot_radius, surface_planes_);
    const eval::MapSurfaceCoverage& held = run.held;
    truth.surface_coverage = held.share;
    truth.surface_visible = held.visible;
    ROS_INFO(
        "mission: the map holds %.1f %% of the %zu surface elements visible from the reachable floor "
        "(%zu candidate scans of %d planes, %.1f s)",
        held.share * 100.0, held.visible, run.candidates, surface_planes_, run.seconds);
    if (mesh_file.empty()) return;
    try {
      const auto t0 = std::chrono::steady_clock::now();
      const eval::AccuracyInput mesh = eval::loadAccuracyInput(mesh_file);
      const eval::WorldSurfaceDistance distance(world);
      const eval::SurfaceAccuracy a = eval::measureSurfaceAccuracy(distance, &run.visible, mesh, start);
      truth.mesh = MeshAccuracy{a.surface_distance.median_m, a.surface_distance.rms_m, a.surface_distance.p95_m,
                                a.coverage, a.triangles};
      ROS_INFO(
          "mission: the mesh (%zu triangles) lies %.1f / %.1f / %.1f mm (median / RMS / 95th percentile) from the "
          "true surfaces and covers %.1f %% of the visible surface within 3 cm (%.1f s)",
          a.triangles, a.surface_distance.median_m * 1e3, a.surface_distance.rms_m * 1e3,
          a.surface_distance.p95_m * 1e3, a.coverage * 100.0,
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    } catch (const std::exception& e) {
      ROS_WARN("mission: the mesh %s was not measured against the world: %s", mesh_file.c_str(), e.what());
    }
  } catch (const std::exception& e) {
    ROS_WARN("mission: no surface coverage (%s: %s)", world_file_.c_str(), e.what());
  }
}

void MissionNode::runMission() {
  if (wait_for_recorder_s_ > 0.0 && status_pub_.getNumSubscribers() == 0) {
    // The recorder subscribes to every topic it records at once; a subscriber of mission/status
    // means it is up. Its connections to the other publishers follow within moments.
    ROS_INFO("mission: waiting up to %.0f s for the recorder (a subscriber of mission/status)", wait_for_recorder_s_);
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(wait_for_recorder_s_);
    while (status_pub_.getNumSubscribers() == 0 && ros::WallTime::now() < until && ros::ok())
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (status_pub_.getNumSubscribers() == 0)
      ROS_WARN("mission: no recorder subscribed within %.0f s; starting without it", wait_for_recorder_s_);
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  }
  const State end = mission_->run();
  const MissionState state = mission_->snapshot();
  try {
    const std::optional<TrueCoverage> truth = trueCoverage(mission_->builtMesh());
    const std::string report =
        writeReport(state, config_.run_dir, listImages(config_.run_dir, "explorer"), truth, html_report_);
    const Summary s = summarize(state);
    std::ostringstream out;
    out << std::fixed << std::setprecision(1) << "mission " << toString(end) << ": " << s.scans << " scans, coverage "
        << s.coverage * 100.0 << " %, " << s.collisions << " collisions, " << s.elapsed_s << " s";
    if (truth) out << " (" << truth->coverage * 100.0 << " % of the truly reachable floor)";
    if (s.ate_scans > 0)
      out << std::setprecision(1) << ", pose error over all scans RMS " << s.ate_rms_m * 100.0 << " cm, max "
          << s.ate_max_m * 100.0 << " cm (odometry alone RMS " << s.odom_ate_rms_m * 100.0 << " cm)";
    if (s.has_ground_truth)
      out << std::setprecision(1) << ", final pose error " << s.slam_error_m * 100.0 << " cm (odometry alone "
          << s.odom_error_m * 100.0 << " cm)";
    ROS_INFO_STREAM(out.str());
    ROS_INFO("mission: map in %s/map, report in %s, summary in %s/summary.json", config_.run_dir.c_str(),
             report.c_str(), config_.run_dir.c_str());
    if (html_report_) {
      // The plots and report.html: a failure costs the pictures, never the mission.
      const std::string problem = runReportScript(report_script_, config_.run_dir, 300.0);
      if (problem.empty())
        ROS_INFO("mission: plots and %s/report.html written by %s", config_.run_dir.c_str(), report_script_.c_str());
      else
        ROS_WARN(
            "mission: no plots or report.html (report.md links them): %s; draw them later with "
            "`rosrun scanstop_mission make_report.py %s`",
            problem.c_str(), config_.run_dir.c_str());
    }
  } catch (const std::exception& e) {
    ROS_ERROR("mission: could not write the report: %s", e.what());
  }
  malloc_trim(0);  // the report's images and the coverage grids are freed: give the heap back
  ros::WallTimerEvent none;
  publishStatus(none);
  running_ = false;
  if (shutdown_when_done_) {
    ros::WallDuration(0.5).sleep();  // let the last status go out
    // A normal end ends the launch calmly: roslaunch is asked to shut down (SIGINT, as Ctrl-C) and
    // stops every node, this one too, instead of reporting a required process that died. Any other
    // end (or a parent that is not roslaunch, e.g. rostest) shuts this node down, and roslaunch
    // reports the required process.
    if (end == State::Done && parentIsRoslaunch()) {
      ROS_INFO("mission: done; ending the launch");
      if (interruptParentLaunch()) return;
    }
    ros::shutdown();
  }
}

void MissionNode::onMasterLost(const std::string& why) {
  std::string refused;
  const bool paused = mission_->pause(&refused);
  paused_for_master_ = paused;
  mission_->note(why + (paused ? "; the mission pauses (its state is kept) until the master is back"
                               : "; the mission stays as it is (" + refused + ")"),
                 true);
  if (paused) ROS_ERROR("mission: paused until the ROS master is back (state kept in %s)", config_.run_dir.c_str());
}

void MissionNode::onMasterBack(const std::string& why) {
  const bool resume = paused_for_master_.exchange(false);
  mission_->note(why + (resume ? "; the mission resumes" : ""));
  if (resume && mission_->resume()) ROS_WARN("mission: resumed: the ROS master is back");
}

void MissionNode::onMasterEnd(const std::string& why) {
  ROS_ERROR("mission: ending the mission: %s", why.c_str());
  mission_->end(why);
  mission_->resume();  // a paused run wakes up and ends
  const bool was_running = running_;
  // The run ends at its next check (a step in a service call first ends as that call does); then
  // the report and summary are written. Then the node ends.
  while (running_) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  if (!was_running) {
    mission_->run();  // not started: ends FAILED at once naming why, and saves the state
    ros::WallTimerEvent none;
    publishStatus(none);
  }
  ros::requestShutdown();
}

bool MissionNode::onStart(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  if (running_) {
    res.success = false;
    res.message = "refused: the mission is already running (state " +
                  std::string(toString(mission_->snapshot().state)) + "); use mission/resume after a pause";
    return true;
  }
  if (runner_.joinable()) runner_.join();
  running_ = true;
  runner_ = std::thread(&MissionNode::runMission, this);
  res.success = true;
  res.message = "mission started";
  return true;
}

bool MissionNode::onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::string why;
  res.success = running_ && mission_->pause(&why);
  res.message = !running_     ? "refused: no mission is running"
                : res.success ? "pausing after the current step"
                              : "refused: " + why;
  return true;
}

bool MissionNode::onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::string why;
  res.success = running_ && mission_->resume(&why);
  res.message = !running_ ? "refused: no mission is running" : res.success ? "resumed" : "refused: " + why;
  return true;
}

bool MissionNode::onAbort(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::string why;
  res.success = running_ && mission_->abort(&why);
  res.message = !running_     ? "refused: no mission is running"
                : res.success ? "aborting after the current step; the state and map are kept"
                              : "refused: " + why;
  return true;
}

void MissionNode::publishStatus(const ros::WallTimerEvent&) {
  const MissionState s = mission_->snapshot();
  scanstop_msgs::MissionStatus msg;
  msg.header.stamp = ros::Time::now();
  msg.header.frame_id = "map";
  msg.state = toString(s.state);
  msg.scan_count = static_cast<uint32_t>(s.scans.size());
  msg.coverage = s.coverage;
  msg.elapsed_s = s.elapsed_s;
  msg.last_error = s.last_error;
  msg.map_pose = ros_conv::toPoseStamped(s.estimate(), "map", msg.header.stamp);
  status_pub_.publish(msg);
}

}  // namespace mission
}  // namespace scanstop
