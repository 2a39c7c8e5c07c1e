#include "scanstop_mission/mission.h"

#include <sys/stat.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace mission {
namespace {

std::string fmt(double v, int precision = 2) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << v;
  return out.str();
}

std::string poseText(const Pose2D& p) {
  return "(" + fmt(p.x) + ", " + fmt(p.y) + ", " + fmt(p.yaw * 180.0 / M_PI, 1) + " deg)";
}

}  // namespace

void MissionConfig::validate() const {
  requireOneOf("planes", planes, {50, 100, 200, 400});
  requireInRange("max_scans", max_scans, 0, 100000);
  requireInRange("d_max", d_max_m, 0.05, 10.0, "m");
  requireInRange("min_scan_travel", min_scan_travel_m, 0.0, 100.0, "m");
  requireInRange("waypoint_tolerance", waypoint_tolerance_m, 0.0, 1.0, "m");
  requireInRange("heading_tolerance", heading_tolerance_rad, 0.0, 0.5, "rad");
  requireInRange("max_step_retries", max_step_retries, 0, 100);
  requireInRange("max_consecutive_failed_cycles", max_consecutive_failed_cycles, 1, 1000);
  requireInRange("max_cycles", max_cycles, 1, 1000000);
  if (run_dir.empty()) throw ConfigError("parameter 'run_dir' is empty: the mission needs a run directory");
}

Mission::Mission(MissionConfig config, RobotSystem& robot, Log info, Log warn)
    : config_(std::move(config)), robot_(robot), info_(std::move(info)), warn_(std::move(warn)) {
  config_.validate();
  if (::mkdir(config_.run_dir.c_str(), 0755) != 0 && errno != EEXIST)
    throw IoError(config_.run_dir, "cannot create the run directory");
  state_.world = config_.world;
}

bool Mission::loadSavedState() {
  std::ifstream probe(statePath());
  if (!probe) return false;
  MissionState loaded = MissionState::load(statePath());
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = loaded;
  if (state_.world.empty()) state_.world = config_.world;
  // Adopt scans SLAM registered after our last save (we died between its answer and our save).
  const int slam_count = robot_.registeredScanCount();
  const int known = state_.scans.empty() ? 0 : state_.scans.back().index + 1;
  for (int i = known; i < slam_count; ++i) {
    const std::optional<Pose2D> pose = robot_.registeredScanPose(i);
    if (!pose) break;
    ScanRecord r;
    r.index = i;
    r.map_pose = *pose;
    r.odom_pose = state_.odom_now;
    state_.scans.push_back(r);
    state_.last_map_pose = *pose;
    state_.odom_at_last_scan = state_.odom_now;
    state_.events.push_back({state_.elapsed_s, "adopted scan " + std::to_string(i) + " registered before a restart"});
  }
  if (state_.state == State::Done || state_.state == State::Aborted || state_.state == State::Failed) {
    // A finished mission is re-opened for viewing; a new run() continues exploring from its map.
    state_.events.push_back({state_.elapsed_s, std::string("re-opened a mission that ended ") + toString(state_.state)});
  }
  state_.state = State::Idle;
  elapsed_at_start_ = state_.elapsed_s;
  return true;
}

double Mission::elapsed() const {
  return elapsed_at_start_ +
         std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
}

void Mission::setState(State s) {
  std::lock_guard<std::mutex> lock(mutex_);
  state_.state = s;
}

void Mission::event(const std::string& what, bool warning) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.events.push_back({elapsed(), what});
    if (warning) state_.last_error = what;
  }
  std::ofstream(logPath(), std::ios::app) << fmt(elapsed(), 1) << " s  " << (warning ? "WARN " : "INFO ") << what << '\n';
  (warning ? warn_ : info_)(what);
}

void Mission::save() {
  std::lock_guard<std::mutex> lock(mutex_);
  state_.elapsed_s = elapsed();
  state_.save(statePath());
}

MissionState Mission::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  MissionState copy = state_;
  if (started_.time_since_epoch().count() != 0) copy.elapsed_s = elapsed();
  return copy;
}

void Mission::pause() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (control_ == Control::Run) control_ = Control::Pause;
}

void Mission::resume() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (control_ == Control::Pause) control_ = Control::Run;
  }
  control_cv_.notify_all();
}

void Mission::abort() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    control_ = Control::Abort;
  }
  control_cv_.notify_all();
}

bool Mission::checkControl() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (control_ == Control::Pause) {
    const State before = state_.state;
    state_.state = State::Paused;
    lock.unlock();
    info_("mission paused; call mission/resume to continue or mission/abort to stop");
    save();
    lock.lock();
    control_cv_.wait(lock, [this] { return control_ != Control::Pause; });
    state_.state = before;
    if (control_ == Control::Run) {
      lock.unlock();
      info_("mission resumed");
      lock.lock();
    }
  }
  return control_ != Control::Abort;
}

bool Mission::budgetReached() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return config_.max_scans > 0 && static_cast<int>(state_.scans.size()) >= config_.max_scans;
}

bool Mission::scanAndRegister() {
  // Scan (retried: a scan changes nothing in the world).
  ScanResult scan;
  for (int attempt = 0; attempt <= config_.max_step_retries; ++attempt) {
    if (!checkControl()) return false;
    setState(State::Scanning);
    scan = robot_.takeScan(config_.planes);
    if (scan.success) break;
    event("scan failed (attempt " + std::to_string(attempt + 1) + "): " + scan.message, true);
  }
  if (!scan.success) return false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.modelled_time_s += scan.duration_s;
    state_.odom_now = scan.odom_pose;
  }
  info_("scan " + std::to_string(snapshot().scans.size()) + ": " + std::to_string(scan.valid_points) + " valid of " +
        std::to_string(scan.raw_points) + " points, " + std::to_string(scan.planes_dropped) + " planes dropped, " +
        fmt(scan.duration_s, 1) + " s modelled");

  // Register (retried only when SLAM did not store the scan: every scan exactly once).
  setState(State::Registering);
  const int before = robot_.registeredScanCount();
  RegisterResult reg;
  for (int attempt = 0; attempt <= config_.max_step_retries; ++attempt) {
    reg = robot_.registerScan(scan);
    if (reg.success) break;
    const int after = robot_.registeredScanCount();
    if (before >= 0 && after > before) {
      if (const std::optional<Pose2D> pose = robot_.registeredScanPose(after - 1)) {
        event("registration answer lost, but SLAM stored scan " + std::to_string(after - 1) + "; adopting its pose", true);
        reg.success = true;
        reg.map_pose = *pose;
        reg.scan_index = static_cast<uint32_t>(after - 1);
        reg.converged = true;
        break;
      }
    }
    event("registration failed (attempt " + std::to_string(attempt + 1) + "): " + reg.message, true);
  }
  if (!reg.success) return false;

  ScanRecord record;
  record.index = static_cast<int>(reg.scan_index);
  record.map_pose = reg.map_pose;
  record.odom_pose = scan.odom_pose;
  record.true_pose = robot_.groundTruth();
  record.converged = reg.converged;
  record.rms_m = reg.rms_m;
  record.valid_points = scan.valid_points;
  record.scan_time_s = scan.duration_s;
  record.register_wall_s = reg.wall_time_s;
  record.plan_wall_s = pending_plan_wall_s_;
  pending_plan_wall_s_ = 0.0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    record.coverage = state_.coverage;
    state_.scans.push_back(record);
    state_.last_map_pose = reg.map_pose;
    state_.odom_at_last_scan = scan.odom_pose;
    state_.odom_now = scan.odom_pose;
  }
  std::string line = "registered scan " + std::to_string(record.index) + " at " + poseText(reg.map_pose) + ", " +
                     std::to_string(reg.iterations) + " iterations, rms " + fmt(reg.rms_m * 1000.0, 1) + " mm, " +
                     fmt(reg.wall_time_s, 2) + " s";
  if (record.true_pose) {
    const Pose2D err = record.true_pose->between(reg.map_pose);
    line += ", error vs ground truth " + fmt(std::hypot(err.x, err.y) * 100.0, 1) + " cm";
  }
  if (!reg.converged) {
    event(line + " -- registration did not converge, SLAM kept the odometry pose: " + reg.message, true);
  } else {
    event(line);
  }
  save();
  return true;
}

bool Mission::driveTo(const Eigen::Vector2d& waypoint, bool& collision) {
  collision = false;
  for (int guard = 0; guard < 100; ++guard) {
    if (!checkControl()) return false;
    const Pose2D est = snapshot().estimate();
    const Eigen::Vector2d delta = waypoint - Eigen::Vector2d(est.x, est.y);
    const double distance = delta.norm();
    if (distance <= config_.waypoint_tolerance_m) return true;
    setState(State::Driving);
    const double turn = normalizeAngle(std::atan2(delta.y(), delta.x()) - est.yaw);
    if (std::abs(turn) > config_.heading_tolerance_rad) {
      const MotionResult r = robot_.rotate(turn);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        state_.modelled_time_s += r.duration_s;
        if (r.success || r.collision) state_.odom_now = r.odom_pose;
      }
      if (!r.success || r.collision) {
        collision = r.collision;
        event("rotation by " + fmt(turn * 180.0 / M_PI, 1) + " deg failed: " + r.message, true);
        return false;
      }
    }
    const double step = std::min(distance, config_.d_max_m);  // never more than d_max in one go
    const MotionResult r = robot_.forward(step);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.modelled_time_s += r.duration_s;
      if (r.success || r.collision) state_.odom_now = r.odom_pose;
    }
    if (r.collision) {
      collision = true;
      event("collision after " + fmt(r.achieved) + " of " + fmt(step) + " m: " + r.message, true);
      return false;
    }
    if (!r.success) {
      event("forward motion of " + fmt(step) + " m failed: " + r.message, true);
      return false;
    }
    save();
  }
  event("could not reach waypoint (" + fmt(waypoint.x()) + ", " + fmt(waypoint.y()) + ") in 100 motions", true);
  return false;
}

State Mission::run() {
  started_ = std::chrono::steady_clock::now();
  info_("mission started in " + config_.run_dir + " (" + std::to_string(config_.planes) + " planes per scan" +
        (config_.max_scans > 0 ? ", at most " + std::to_string(config_.max_scans) + " scans" : std::string()) + ")");
  const auto finish = [this](State s, const std::string& why) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.state = s;
    }
    event(std::string("mission ") + toString(s) + ": " + why, s == State::Failed);
    save();
    return s;
  };

  if (snapshot().scans.empty() && !scanAndRegister())
    return checkControl() ? finish(State::Failed, "could not take and register the first scan: " + snapshot().last_error)
                          : finish(State::Aborted, "aborted by the user");

  int failed_cycles = 0;
  for (int cycle = 0; cycle < config_.max_cycles; ++cycle) {
    if (!checkControl()) return finish(State::Aborted, "aborted by the user");
    if (failed_cycles >= config_.max_consecutive_failed_cycles)
      return finish(State::Failed, std::to_string(failed_cycles) + " cycles in a row made no progress; last error: " +
                                       snapshot().last_error);

    // Plan.
    setState(State::Planning);
    PlanResult plan;
    const MissionState now = snapshot();
    for (int attempt = 0; attempt <= config_.max_step_retries; ++attempt) {
      plan = robot_.planNext(now.estimate(), now.unreachable);
      if (plan.success) break;
      event("planning failed (attempt " + std::to_string(attempt + 1) + "): " + plan.message, true);
    }
    if (!plan.success) return finish(State::Failed, "the explorer could not plan: " + plan.message);
    pending_plan_wall_s_ += plan.wall_time_s;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.plans += 1;
      state_.coverage = plan.coverage;
      state_.modelled_time_s += plan.duration_s;
      if (!state_.scans.empty()) state_.scans.back().coverage = plan.coverage;
    }
    if (plan.complete) {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.complete = true;
      state_.complete_reason = plan.complete_reason;
    }
    if (plan.complete) break;
    if (budgetReached()) {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.complete_reason = "scan budget of " + std::to_string(config_.max_scans) + " scans reached";
      break;
    }
    if (plan.waypoints.empty()) {
      ++failed_cycles;
      event("the explorer returned an empty path without completing; replanning", true);
      continue;
    }
    info_("plan " + std::to_string(now.plans + 1) + ": target (" + fmt(plan.target.x()) + ", " + fmt(plan.target.y()) +
          "), " + std::to_string(plan.waypoints.size()) + " waypoints, score " + fmt(plan.score, 4) + ", coverage " +
          fmt(plan.coverage * 100.0, 1) + " %");
    save();

    // Drive the path, scanning where the plan says.
    const size_t scans_before = snapshot().scans.size();
    bool replan = false;
    double travel = 0.0;  // planned path length since the last scan [m]
    Eigen::Vector2d from(now.estimate().x, now.estimate().y);
    for (size_t i = 0; i < plan.waypoints.size() && !replan; ++i) {
      travel += (plan.waypoints[i] - from).norm();
      from = plan.waypoints[i];
      bool collision = false;
      if (!driveTo(plan.waypoints[i], collision)) {
        if (!checkControl()) return finish(State::Aborted, "aborted by the user");
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (collision) state_.collisions += 1;
          state_.unreachable.push_back(plan.target);
        }
        event("target (" + fmt(plan.target.x()) + ", " + fmt(plan.target.y()) +
                  ") marked unreachable; scanning here to re-localize, then replanning",
              true);
        if (!scanAndRegister() && !checkControl()) return finish(State::Aborted, "aborted by the user");
        replan = true;
        break;
      }
      const bool last = i + 1 == plan.waypoints.size();
      const bool landmark = i < plan.scan_at.size() && plan.scan_at[i];
      const bool scan_here = last || (landmark && travel >= config_.min_scan_travel_m);
      if (scan_here) {
        travel = 0.0;
        if (!scanAndRegister()) {
          if (!checkControl()) return finish(State::Aborted, "aborted by the user");
          replan = true;
        }
        if (budgetReached()) break;
      }
    }
    failed_cycles = snapshot().scans.size() > scans_before ? 0 : failed_cycles + 1;
  }

  const MissionState end = snapshot();
  if (!end.complete && end.complete_reason.empty())
    return finish(State::Failed, "stopped after " + std::to_string(config_.max_cycles) + " cycles");

  if (config_.build_mesh) {
    setState(State::Meshing);
    const MeshResult mesh = robot_.buildMesh(config_.run_dir + "/mesh.ply");
    if (!mesh.available)
      info_("no mesher is running; skipping the mesh");
    else if (mesh.success)
      event("mesh with " + std::to_string(mesh.triangles) + " triangles written to " + mesh.file);
    else
      event("meshing failed: " + mesh.message, true);
  }
  return finish(State::Done, end.complete ? "exploration complete: " + end.complete_reason : end.complete_reason);
}

}  // namespace mission
}  // namespace scanstop
