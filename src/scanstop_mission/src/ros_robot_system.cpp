#include "scanstop_mission/ros_robot_system.h"

#include <geometry_msgs/Point.h>
#include <scanstop_msgs/BuildMesh.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/PlanNext.h>
#include <scanstop_msgs/RegisterScan.h>
#include <scanstop_msgs/Rotate.h>
#include <scanstop_msgs/TakeScan.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <thread>

#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/msg_conversion.h"

namespace scanstop {
namespace mission {
namespace {

/// Calls a service on a worker thread and waits at most timeout_s for the answer. A call that does
/// not answer in time is abandoned (its thread ends when roscpp gives up on the connection).
/// Returns false with `error` set when the service is missing, the call fails or times out.
template <typename Srv>
bool callWithTimeout(ros::ServiceClient client, Srv& srv, double wait_s, double timeout_s, std::string& error,
                     double& wall_s) {
  const auto start = std::chrono::steady_clock::now();
  if (!client.waitForExistence(ros::Duration(wait_s))) {
    error = "service " + client.getService() + " is not available (waited " + std::to_string(static_cast<int>(wait_s)) +
            " s); is its node running?";
    return false;
  }
  struct Call {
    std::mutex m;
    std::condition_variable cv;
    bool done = false;
    bool ok = false;
    Srv srv;
  };
  auto call = std::make_shared<Call>();
  call->srv = srv;
  std::thread([call, client]() mutable {
    const bool ok = client.call(call->srv);
    std::lock_guard<std::mutex> lock(call->m);
    call->ok = ok;
    call->done = true;
    call->cv.notify_all();
  }).detach();
  std::unique_lock<std::mutex> lock(call->m);
  const bool answered =
      call->cv.wait_for(lock, std::chrono::duration<double>(timeout_s), [&call] { return call->done; });
  wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!answered) {
    error = "service " + client.getService() + " gave no answer within " + std::to_string(static_cast<int>(timeout_s)) +
            " s";
    return false;
  }
  if (!call->ok) {
    error = "service " + client.getService() + " call failed (the node died or refused the request)";
    return false;
  }
  srv = call->srv;
  return true;
}

Pose2D poseOf(const geometry_msgs::PoseStamped& p) {
  try {
    return ros_conv::fromPoseMsg(p.pose);
  } catch (const std::exception&) {
    return Pose2D();
  }
}

template <typename Result, typename Response>
void copyStep(Result& r, const Response& res) {
  r.success = res.success;
  r.message = res.message;
  r.duration_s = res.duration_s;
}

}  // namespace

RosRobotSystem::RosRobotSystem(ros::NodeHandle& nh, const CallTimeouts& timeouts, const std::string& map_dir)
    : nh_(nh), timeouts_(timeouts), map_dir_(map_dir) {
  take_scan_ = nh_.serviceClient<scanstop_msgs::TakeScan>("scanner/take_scan");
  register_scan_ = nh_.serviceClient<scanstop_msgs::RegisterScan>("slam/register_scan");
  rotate_ = nh_.serviceClient<scanstop_msgs::Rotate>("base/rotate");
  forward_ = nh_.serviceClient<scanstop_msgs::Forward>("base/forward");
  plan_next_ = nh_.serviceClient<scanstop_msgs::PlanNext>("explorer/plan_next");
  build_mesh_ = nh_.serviceClient<scanstop_msgs::BuildMesh>("mesher/build_mesh");
  ground_truth_sub_ = nh_.subscribe("ground_truth", 10, &RosRobotSystem::onGroundTruth, this);
  odom_sub_ = nh_.subscribe("odom", 10, &RosRobotSystem::onOdometry, this);
  slam_path_sub_ = nh_.subscribe("slam/path", 1, &RosRobotSystem::onSlamPath, this);
  clearance_sub_ = nh_.subscribe("ground_truth/clearance", 100, &RosRobotSystem::onClearance, this);
}

void RosRobotSystem::onClearance(const scanstop_msgs::MotionClearance::ConstPtr& msg) {
  if (!std::isfinite(msg->min_clearance_m)) {
    ROS_WARN_THROTTLE(10.0, "ignoring a ground_truth/clearance message with a non-finite clearance");
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  clearance_ = *msg;
}

std::optional<double> RosRobotSystem::takeClearance() {
  if (clearance_sub_.getNumPublishers() == 0) return std::nullopt;  // a real robot: no ground truth
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(0.5);
  while (ros::ok()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (clearance_ && static_cast<long>(clearance_->motion_index) != clearance_taken_) {
        clearance_taken_ = static_cast<long>(clearance_->motion_index);
        return clearance_->min_clearance_m;
      }
    }
    if (ros::WallTime::now() >= deadline) break;
    ros::WallDuration(0.005).sleep();
  }
  return std::nullopt;
}

void RosRobotSystem::onSlamPath(const nav_msgs::Path::ConstPtr& msg) {
  std::vector<Pose2D> poses;
  try {
    for (const auto& p : msg->poses) poses.push_back(ros_conv::fromPoseMsg(p.pose));
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(10.0, "ignoring a malformed slam/path message: %s", e.what());
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  slam_path_ = std::move(poses);
}

void RosRobotSystem::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  try {
    const Pose2D p = ros_conv::fromPoseMsg(msg->pose.pose);
    std::lock_guard<std::mutex> lock(mutex_);
    odom_ = p;
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(10.0, "ignoring a malformed odom message: %s", e.what());
  }
}

std::optional<Pose2D> RosRobotSystem::currentOdometry() {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeouts_.wait_for_service_timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (odom_) return odom_;
    }
    ros::WallDuration(0.05).sleep();
  }
  return std::nullopt;
}

void RosRobotSystem::onGroundTruth(const nav_msgs::Odometry::ConstPtr& msg) {
  try {
    const Pose2D p = ros_conv::fromPoseMsg(msg->pose.pose);
    std::lock_guard<std::mutex> lock(mutex_);
    ground_truth_ = p;
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(10.0, "ignoring a malformed ground_truth message: %s", e.what());
  }
}

std::optional<Pose2D> RosRobotSystem::groundTruth() {
  // The simulator publishes the true pose after every step; give the last message a moment to arrive.
  ros::WallDuration(0.05).sleep();
  std::lock_guard<std::mutex> lock(mutex_);
  return ground_truth_;
}

ScanResult RosRobotSystem::takeScan(int planes) {
  ScanResult r;
  auto srv = std::make_shared<scanstop_msgs::TakeScan>();
  srv->request.planes = static_cast<uint16_t>(planes);
  if (!callWithTimeout(take_scan_, *srv, timeouts_.wait_for_service_timeout_s, timeouts_.scan_timeout_s, r.message,
                       r.wall_time_s))
    return r;
  copyStep(r, srv->response);
  r.odom_pose = poseOf(srv->response.odom_pose);
  r.raw_points = srv->response.counts.raw_points;
  r.valid_points = srv->response.counts.valid_points;
  r.planes_dropped = srv->response.counts.planes_dropped;
  try {
    PointCloud cloud = ros_conv::fromMsg(srv->response.cloud);  // base_link
    r.points_base.reserve(cloud.points.size());
    for (const Eigen::Vector3f& p : cloud.points)
      if (p.allFinite()) r.points_base.push_back(p);
  } catch (const std::exception& e) {
    ROS_WARN("mission: the scan's points cannot be read for the leg check (%s); legs go unchecked until the next scan",
             e.what());
  }
  r.payload = srv;
  return r;
}

RegisterResult RosRobotSystem::registerScan(const ScanResult& scan) {
  RegisterResult r;
  const auto taken = std::any_cast<std::shared_ptr<scanstop_msgs::TakeScan>>(scan.payload);
  scanstop_msgs::RegisterScan srv;
  srv.request.cloud = taken->response.cloud;
  srv.request.odom_pose = taken->response.odom_pose;
  if (!callWithTimeout(register_scan_, srv, timeouts_.wait_for_service_timeout_s, timeouts_.register_timeout_s,
                       r.message, r.wall_time_s))
    return r;
  copyStep(r, srv.response);
  r.map_pose = poseOf(srv.response.map_pose);
  r.converged = srv.response.converged;
  r.iterations = srv.response.iterations;
  r.correspondences = srv.response.correspondences;
  r.rms_m = srv.response.rms_m;
  r.scan_index = srv.response.scan_index;
  return r;
}

MotionResult RosRobotSystem::rotate(double angle_rad) {
  MotionResult r;
  scanstop_msgs::Rotate srv;
  srv.request.angle_rad = angle_rad;
  if (!callWithTimeout(rotate_, srv, timeouts_.wait_for_service_timeout_s, timeouts_.motion_timeout_s, r.message,
                       r.wall_time_s))
    return r;
  copyStep(r, srv.response);
  r.achieved = srv.response.achieved_angle_rad;
  r.odom_pose = poseOf(srv.response.odom_pose);
  r.collision = srv.response.collision;
  r.true_clearance_m = takeClearance();
  return r;
}

MotionResult RosRobotSystem::forward(double distance_m) {
  MotionResult r;
  scanstop_msgs::Forward srv;
  srv.request.distance_m = distance_m;
  if (!callWithTimeout(forward_, srv, timeouts_.wait_for_service_timeout_s, timeouts_.motion_timeout_s, r.message,
                       r.wall_time_s))
    return r;
  copyStep(r, srv.response);
  r.achieved = srv.response.achieved_distance_m;
  r.odom_pose = poseOf(srv.response.odom_pose);
  r.collision = srv.response.collision;
  r.true_clearance_m = takeClearance();
  return r;
}

PlanResult RosRobotSystem::planNext(const Pose2D& map_pose, const std::vector<Eigen::Vector2d>& unreachable,
                                    const std::vector<Contact>& contacts, const std::optional<Eigen::Vector2d>& goal) {
  PlanResult r;
  scanstop_msgs::PlanNext srv;
  srv.request.map_pose = ros_conv::toPoseStamped(map_pose, "map", ros::Time::now());
  for (const auto& u : unreachable) {
    geometry_msgs::Point p;
    p.x = u.x();
    p.y = u.y();
    srv.request.unreachable.push_back(p);
  }
  for (const Contact& c : contacts) {
    geometry_msgs::Point p;
    p.x = c.point.x();
    p.y = c.point.y();
    srv.request.contacts.push_back(p);
    srv.request.contact_radii.push_back(c.radius_m);
  }
  if (goal) {
    srv.request.to_goal = true;
    srv.request.goal.x = goal->x();
    srv.request.goal.y = goal->y();
  }
  if (!mesher_seen_ && build_mesh_.exists()) mesher_seen_ = true;  // a mesher runs: wait for it at the end
  if (!callWithTimeout(plan_next_, srv, timeouts_.wait_for_service_timeout_s, timeouts_.plan_timeout_s, r.message,
                       r.wall_time_s))
    return r;
  copyStep(r, srv.response);
  for (const auto& p : srv.response.path.poses) r.waypoints.emplace_back(p.pose.position.x, p.pose.position.y);
  for (const auto flag : srv.response.scan_at) r.scan_at.push_back(flag != 0);
  if (srv.response.clearance.size() == r.waypoints.size()) r.clearance_m = srv.response.clearance;
  r.target = Eigen::Vector2d(srv.response.target.pose.position.x, srv.response.target.pose.position.y);
  r.score = srv.response.score;
  r.complete = srv.response.exploration_complete;
  r.complete_reason = srv.response.complete_reason;
  r.coverage = srv.response.coverage;
  r.d_max_m = std::isfinite(srv.response.d_max_m) && srv.response.d_max_m > 0.0 ? srv.response.d_max_m : 0.0;
  return r;
}

MeshResult RosRobotSystem::buildMesh(const std::string& output_path) {
  MeshResult r;
  // A mesher seen during the mission may be restarting (respawn): wait for it as for any service.
  // One never seen gets a short look only: no mesher is not an error.
  const double wait_s =
      mesher_seen_ ? timeouts_.wait_for_service_timeout_s : std::min(2.0, timeouts_.wait_for_service_timeout_s);
  if (!build_mesh_.waitForExistence(ros::Duration(wait_s))) {
    r.available = false;
    return r;
  }
  mesher_seen_ = true;
  r.available = true;
  scanstop_msgs::BuildMesh srv;
  srv.request.output_path = output_path;
  if (!callWithTimeout(build_mesh_, srv, timeouts_.wait_for_service_timeout_s, timeouts_.mesh_timeout_s, r.message,
                       r.wall_time_s))
    return r;
  copyStep(r, srv.response);
  r.triangles = srv.response.triangles;
  r.file = srv.response.file;
  return r;
}

// The SLAM map as the mission can see it: the map directory when it is on this host (the same run
// directory), else slam/path (latched; SLAM on another host). The larger of the two counts wins: the
// path message may still be on its way when the map directory is already written, and vice versa.
int RosRobotSystem::registeredScanCount() {
  int from_dir = -1;
  try {
    from_dir = static_cast<int>(MapDirectory(map_dir_).nextIndex());  // indices may have gaps (skipped scans)
  } catch (const std::exception& e) {
    ROS_WARN("cannot read the SLAM map directory %s: %s", map_dir_.c_str(), e.what());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  return std::max(from_dir, slam_path_.empty() ? from_dir : static_cast<int>(slam_path_.size()));
}

std::vector<std::pair<int, Pose2D>> RosRobotSystem::registeredScanPoses() {
  std::vector<std::pair<int, Pose2D>> out;
  try {
    const MapDirectory map(map_dir_);  // poses.csv as SLAM last wrote it (atomically)
    for (const MapScanInfo& s : map.scans()) out.emplace_back(static_cast<int>(s.index), s.map_pose);
    return out;
  } catch (const std::exception& e) {
    ROS_WARN("cannot read the SLAM map directory %s: %s", map_dir_.c_str(), e.what());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  for (size_t i = 0; i < slam_path_.size(); ++i) out.emplace_back(static_cast<int>(i), slam_path_[i]);
  return out;
}

std::optional<Pose2D> RosRobotSystem::registeredScanPose(int index) {
  try {
    const MapDirectory map(map_dir_);
    // By scan index, not position: a corrupt scan skipped by the loader leaves a gap.
    for (const MapScanInfo& s : map.scans())
      if (static_cast<int>(s.index) == index) return s.map_pose;
  } catch (const std::exception& e) {
    ROS_WARN("cannot read the SLAM map directory %s: %s", map_dir_.c_str(), e.what());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (index >= 0 && index < static_cast<int>(slam_path_.size())) return slam_path_[index];
  return std::nullopt;
}

std::optional<Pose2D> RosRobotSystem::registeredScanOdometry(int index) {
  try {
    const MapDirectory map(map_dir_);
    // By scan index, not position: a corrupt scan skipped by the loader leaves a gap.
    for (const MapScanInfo& s : map.scans())
      if (static_cast<int>(s.index) == index) return s.odom_pose;
  } catch (const std::exception& e) {
    ROS_WARN("cannot read the SLAM map directory %s: %s", map_dir_.c_str(), e.what());
  }
  return std::nullopt;
}

}  // namespace mission
}  // namespace scanstop
