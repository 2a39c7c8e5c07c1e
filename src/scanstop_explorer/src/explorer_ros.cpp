#include "scanstop_explorer/explorer_ros.h"

#include <nav_msgs/Path.h>
#include <sys/stat.h>
#include <visualization_msgs/Marker.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_common/ros/robot_body.h"
#include "scanstop_explorer/parameters.h"
#include "scanstop_explorer/render.h"

namespace scanstop {
namespace explorer {

namespace {
bool isDirectory(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}
}  // namespace

void readParameters(const ros::NodeHandle& pnh, ExplorerConfig& c, NodeConfig& n) {
  ros_params::ParamReader params(pnh, "explorer_node");
  params.known({"robot_body"});  // readRobotBody() below, when the body is set in this namespace
  params.optional("frame_id", n.frame_id);
  double master_timeout_s = 30.0;  // main() reads it for the master watchdog; a known name here (and its type checked)
  params.optional("master_timeout_s", master_timeout_s);
  bool end_launch = false;  // read by main() after a start-up error; a known name here
  params.optional("end_launch_on_setup_error", end_launch);
  params.optional("map_dir", n.map_dir);
  params.optional("run_dir", n.run_dir);
  params.optional("image_scale", n.image_scale);
  params.optional("max_coordinate_m", n.max_coordinate_m);
  params.optional("max_unreachable", n.max_unreachable);
  params.optional("max_point_distance_m", n.max_point_distance_m);
  // ROS parameter names are the config fields' names (so a ConfigError names the parameter); the
  // one list (parameters.h) that the offline tools' --config reads too.
  forEachParameter(c, [&](const char* name, auto& value) { params.optional(name, value); });
  // The body (robot_body/..., config/robot_body.yaml) gives the inflation and the obstacle layer:
  // robot_radius_m = radius + inflation_margin_m, the layer's top = height + obstacle_height_margin_m.
  // ~robot_radius_m / ~robot_height_m set explicitly override them (a WARN names both).
  const RobotBody body = ros_params::readRobotBody(pnh);
  BodyMargins margins;
  params.optional("inflation_margin_m", margins.inflation_margin_m);
  params.optional("obstacle_height_margin_m", margins.obstacle_height_margin_m);
  requireInRange(pnh.resolveName("inflation_margin_m"), margins.inflation_margin_m, 0.0, 1.0, "m");
  requireInRange(pnh.resolveName("obstacle_height_margin_m"), margins.obstacle_height_margin_m, 0.0, 1.0, "m");
  applyBody(body, margins, c);
  const auto override_body = [&](const std::string& name, double& value, double from_body) {
    if (!params.optional(name, value)) return;
    ROS_WARN("explorer_node: %s = %.3f m overrides %.3f m from the robot body (config/robot_body.yaml)",
             pnh.resolveName(name).c_str(), value, from_body);
  };
  override_body("robot_radius_m", c.planner.robot_radius_m, c.planner.robot_radius_m);
  override_body("robot_height_m", c.floor.robot_height_m, c.floor.robot_height_m);
  params.rejectUnknown();
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError("parameter in namespace " + pnh.getNamespace() + ": " + e.what());
  }
  requireInRange(pnh.resolveName("image_scale"), n.image_scale, 1, 16);
  requireInRange(pnh.resolveName("max_coordinate_m"), n.max_coordinate_m, 1.0, 1e6, "m");
  requireInRange(pnh.resolveName("max_unreachable"), n.max_unreachable, 0, 1e6);
  requireInRange(pnh.resolveName("max_point_distance_m"), n.max_point_distance_m, 0.1, 1000.0, "m");
  if (n.frame_id.empty() || n.frame_id.front() == '/' || n.frame_id.find(' ') != std::string::npos)
    throw ConfigError("parameter '" + pnh.resolveName("frame_id") + "' = '" + n.frame_id +
                      "' must be a non-empty frame id without a leading '/' or spaces");
  // With its parents: the run directory may not exist yet when this node starts before icp_slam_node
  // (two_host_workstation.launch: a single mkdir failed there and only a respawn got past it).
  if (!n.run_dir.empty()) try {
      makeDirectories(n.run_dir);
    } catch (const IoError& e) {
      throw ConfigError("parameter '" + pnh.resolveName("run_dir") + "' = '" + n.run_dir + "': " + e.what());
    }
}

std::string planRequestProblem(const scanstop_msgs::PlanNext::Request& req, const NodeConfig& c) {
  std::ostringstream out;
  const std::string& frame = req.map_pose.header.frame_id;
  if (!frame.empty() && frame != c.frame_id)
    return "map_pose is in frame '" + frame + "', expected '" + c.frame_id + "'";
  const auto& p = req.map_pose.pose.position;
  const auto& q = req.map_pose.pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    out << "map_pose.position (" << p.x << ", " << p.y << ", " << p.z << ") is not finite";
    return out.str();
  }
  if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) {
    out << "map_pose.orientation (" << q.x << ", " << q.y << ", " << q.z << ", " << q.w << ") is not finite";
    return out.str();
  }
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (std::abs(norm - 1.0) > 1e-3) {
    out << "map_pose.orientation (" << q.x << ", " << q.y << ", " << q.z << ", " << q.w
        << ") is not a unit quaternion (norm " << norm << ")";
    return out.str();
  }
  if (std::hypot(p.x, p.y) > c.max_coordinate_m) {
    out << "map_pose.position (" << p.x << ", " << p.y << ") is " << std::hypot(p.x, p.y)
        << " m from the map origin, beyond max_coordinate_m " << c.max_coordinate_m << " m";
    return out.str();
  }
  if (req.to_goal && (!std::isfinite(req.goal.x) || !std::isfinite(req.goal.y) ||
                      std::hypot(req.goal.x, req.goal.y) > c.max_coordinate_m)) {
    out << "goal (" << req.goal.x << ", " << req.goal.y << ") is not finite or beyond max_coordinate_m "
        << c.max_coordinate_m << " m from the map origin";
    return out.str();
  }
  if (req.unreachable.size() > static_cast<size_t>(c.max_unreachable)) {
    out << "unreachable has " << req.unreachable.size() << " points, more than max_unreachable " << c.max_unreachable;
    return out.str();
  }
  if (req.contacts.size() > static_cast<size_t>(c.max_unreachable)) {
    out << "contacts has " << req.contacts.size() << " points, more than max_unreachable " << c.max_unreachable;
    return out.str();
  }
  if (!req.contact_radii.empty() && req.contact_radii.size() != req.contacts.size()) {
    out << "contact_radii has " << req.contact_radii.size() << " values for " << req.contacts.size()
        << " contacts (empty, or one per contact)";
    return out.str();
  }
  for (size_t i = 0; i < req.contact_radii.size(); ++i)
    if (!std::isfinite(req.contact_radii[i]) || req.contact_radii[i] < 0.0 || req.contact_radii[i] > 2.0) {
      out << "contact_radii[" << i << "] " << req.contact_radii[i] << " m is not in [0, 2] (0: contact_radius_m)";
      return out.str();
    }
  for (const auto* list : {&req.unreachable, &req.contacts}) {
    const char* name = list == &req.unreachable ? "unreachable" : "contacts";
    for (size_t i = 0; i < list->size(); ++i) {
      const geometry_msgs::Point& u = (*list)[i];
      if (!std::isfinite(u.x) || !std::isfinite(u.y) || !std::isfinite(u.z)) {
        out << name << "[" << i << "] (" << u.x << ", " << u.y << ", " << u.z << ") is not finite";
        return out.str();
      }
      if (std::hypot(u.x, u.y) > c.max_coordinate_m) {
        out << name << "[" << i << "] (" << u.x << ", " << u.y << ") is beyond max_coordinate_m " << c.max_coordinate_m
            << " m from the map origin";
        return out.str();
      }
    }
  }
  return "";
}

ExplorerNode::ExplorerNode(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh) {
  ExplorerConfig config;
  readParameters(pnh, config, node_config_);
  config_text_ = parameterFileText(config, "explorer_node " + pnh.getNamespace() +
                                               ": the parameters of this run, the robot body applied\n"
                                               "(plan_step --config and floor_coverage --config read this file)");
  explorer_ = std::make_unique<Explorer>(config);
  loadMapDir();
  // Number the steps on from what an earlier run left in run_dir (a restarted node loses nothing).
  step_ = 1;
  for (;; ++step_) {
    char name[64];
    std::snprintf(name, sizeof(name), "/step_%03u_plan.json", step_);
    struct stat st;
    if (node_config_.run_dir.empty() || ::stat((node_config_.run_dir + name).c_str(), &st) != 0) break;
  }
  // Relative names, meant to be remapped.
  floor_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/floor", 1, true);
  accessible_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/accessible", 1, true);
  distance_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/distance", 1, true);
  cost_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/cost", 1, true);
  knowledge_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/knowledge", 1, true);
  evaluation_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("explorer/evaluation", 1, true);
  skeleton_pub_ = nh_.advertise<visualization_msgs::Marker>("explorer/skeleton", 1, true);
  landmarks_pub_ = nh_.advertise<visualization_msgs::Marker>("explorer/landmarks", 1, true);
  path_pub_ = nh_.advertise<nav_msgs::Path>("explorer/path", 1, true);
  scan_sub_ = nh_.subscribe("slam/registered_scan", 20, &ExplorerNode::onScan, this);
  plan_srv_ = nh_.advertiseService("explorer/plan_next", &ExplorerNode::onPlanNext, this);
  ROS_INFO("explorer_node: ready with %zu scans (map_dir '%s', run_dir '%s')", explorer_->scanCount(),
           node_config_.map_dir.c_str(), node_config_.run_dir.c_str());
}

void ExplorerNode::loadMapDir() {
  if (node_config_.map_dir.empty()) return;
  if (!isDirectory(node_config_.map_dir)) {
    ROS_WARN_ONCE("explorer_node: map_dir '%s' does not exist (yet); waiting for scans on the topic",
                  node_config_.map_dir.c_str());
    return;
  }
  try {
    std::vector<std::string> problems;
    size_t moved = 0;
    const size_t added = explorer_->loadMapDirectory(MapDirectory(node_config_.map_dir), &problems, &moved);
    if (added) ROS_INFO("explorer_node: loaded %zu scans from %s", added, node_config_.map_dir.c_str());
    // SLAM's relaxation corrected earlier poses (poses.csv): the floor grid was rebuilt at them.
    if (moved)
      ROS_INFO("explorer_node: %zu scans moved in %s/poses.csv: floor grid rebuilt at the corrected poses", moved,
               node_config_.map_dir.c_str());
    for (const std::string& p : problems) ROS_ERROR("explorer_node: map_dir: %s", p.c_str());
  } catch (const std::exception& e) {
    ROS_ERROR("explorer_node: cannot load map_dir: %s", e.what());
  }
}

void ExplorerNode::onScan(const scanstop_msgs::RegisteredScan& msg) {
  if (explorer_->hasScan(msg.scan_index)) return;
  const std::string& frame = msg.cloud.header.frame_id.empty() ? msg.header.frame_id : msg.cloud.header.frame_id;
  if (frame != node_config_.frame_id) {
    ROS_ERROR("explorer_node: scan %u is in frame '%s', expected '%s'; skipped", msg.scan_index, frame.c_str(),
              node_config_.frame_id.c_str());
    return;
  }
  try {
    const geometry_msgs::Pose& pose = msg.pose.pose;
    if (!std::isfinite(pose.position.x) || !std::isfinite(pose.position.y) ||
        std::hypot(pose.position.x, pose.position.y) > node_config_.max_coordinate_m)
      throw std::invalid_argument("its pose is not finite or beyond max_coordinate_m");
    const PointCloud cloud = ros_conv::fromMsg(msg.cloud);
    const Eigen::Vector2f at(static_cast<float>(pose.position.x), static_cast<float>(pose.position.y));
    for (size_t i = 0; i < cloud.points.size(); ++i)
      if (cloud.points[i].allFinite() && (cloud.points[i].head<2>() - at).norm() > node_config_.max_point_distance_m)
        throw std::invalid_argument("point " + std::to_string(i) + " is farther than max_point_distance_m " +
                                    std::to_string(node_config_.max_point_distance_m) + " m from the scan pose");
    explorer_->addScan(msg.scan_index, ros_conv::fromPoseMsg(msg.pose.pose), cloud.points);
  } catch (const std::exception& e) {
    ROS_ERROR("explorer_node: scan %u rejected: %s", msg.scan_index, e.what());
  }
}

bool ExplorerNode::onPlanNext(scanstop_msgs::PlanNext::Request& req, scanstop_msgs::PlanNext::Response& res) {
  const auto t0 = std::chrono::steady_clock::now();
  auto finish = [&]() {
    res.duration_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return true;
  };
  // Everything is checked before anything is applied (map directory, blacklist, step counter).
  const std::string problem = planRequestProblem(req, node_config_);
  if (!problem.empty()) {
    res.success = false;
    res.message = "bad request: " + problem;
    res.complete_reason = res.message;
    ROS_WARN("explorer_node: refused plan_next: %s", problem.c_str());
    return finish();
  }
  const Pose2D robot = ros_conv::fromPoseMsg(req.map_pose.pose);
  loadMapDir();  // scans published before this node started
  for (const geometry_msgs::Point& u : req.unreachable)
    if (explorer_->markUnreachable(Eigen::Vector2d(u.x, u.y)))
      ROS_INFO("explorer_node: target (%.2f, %.2f) blacklisted as unreachable by the caller", u.x, u.y);
  for (size_t i = 0; i < req.contacts.size(); ++i) {
    const geometry_msgs::Point& p = req.contacts[i];
    const double radius = i < req.contact_radii.size() ? req.contact_radii[i] : 0.0;
    if (explorer_->addContact(Eigen::Vector2d(p.x, p.y), radius))
      ROS_WARN("explorer_node: contact at (%.2f, %.2f) reported by the caller: an obstacle disc of %.2f m from now on",
               p.x, p.y, explorer_->contacts().back().second);
  }
  const PlanResult r = explorer_->plan(
      robot, req.to_goal ? std::optional<Eigen::Vector2d>(Eigen::Vector2d(req.goal.x, req.goal.y)) : std::nullopt);
  const ros::Time now = ros::Time::now();
  res.success = r.success;
  res.message = r.message;
  res.exploration_complete = r.complete;
  res.complete_reason = r.success ? r.complete_reason : r.message;
  res.coverage = r.coverage;
  res.scans = static_cast<uint32_t>(explorer_->scanCount());
  res.d_max_m = explorer_->config().planner.d_max_m;
  res.floor_area_m2 = r.floor_area_m2;
  res.accessible_area_m2 = r.accessible_area_m2;
  res.score = r.score;
  res.target = ros_conv::toPoseStamped(Pose2D(r.target.x(), r.target.y(), robot.yaw), node_config_.frame_id, now);
  res.path.header.frame_id = node_config_.frame_id;
  res.path.header.stamp = now;
  for (size_t i = 0; i < r.path.size(); ++i) {
    // Heading along the next leg (the last waypoint keeps the previous leg's heading).
    double yaw = robot.yaw;
    if (r.path.size() > 1) {
      const size_t a = i + 1 < r.path.size() ? i : i - 1;
      const Eigen::Vector2d d = r.path[a + 1] - r.path[a];
      if (d.norm() > 1e-9) yaw = std::atan2(d.y(), d.x());
    }
    res.path.poses.push_back(
        ros_conv::toPoseStamped(Pose2D(r.path[i].x(), r.path[i].y(), yaw), node_config_.frame_id, now));
    res.scan_at.push_back(r.scan_at[i]);
    res.clearance.push_back(i < r.clearance_m.size() ? r.clearance_m[i] : 0.0);
  }
  if (r.success) {
    publish(r);
    path_pub_.publish(res.path);
    writeImages(r);
  }
  ROS_INFO("explorer_node: plan %u: %s%s", step_, r.message.c_str(),
           r.complete ? (" (" + r.complete_reason + ")").c_str() : "");
  if (r.success) ++step_;
  return finish();
}

nav_msgs::OccupancyGrid ExplorerNode::gridMsg(const PlanResult& r) const {
  nav_msgs::OccupancyGrid g;
  g.header.frame_id = node_config_.frame_id;
  g.header.stamp = ros::Time::now();
  g.info.map_load_time = g.header.stamp;
  g.info.resolution = static_cast<float>(r.geometry.resolution);
  g.info.width = static_cast<uint32_t>(r.geometry.width);
  g.info.height = static_cast<uint32_t>(r.geometry.height);
  g.info.origin.position.x = r.geometry.origin_x;
  g.info.origin.position.y = r.geometry.origin_y;
  g.info.origin.orientation.w = 1.0;
  return g;
}

void ExplorerNode::publish(const PlanResult& r) {
  auto send = [&](ros::Publisher& pub, std::vector<int8_t> data) {
    nav_msgs::OccupancyGrid g = gridMsg(r);
    g.data = std::move(data);
    pub.publish(g);
  };
  send(floor_pub_, statesToOccupancy(r.states));
  send(accessible_pub_, accessibleToOccupancy(r.states, r.accessible));
  cv::Mat d;
  r.sq_dt.convertTo(d, CV_32F);
  cv::sqrt(d, d);
  send(distance_pub_, scaledToOccupancy(d, r.accessible));
  send(cost_pub_, scaledToOccupancy(r.cost_map.cost, r.cost_map.predecessor >= 0));
  send(knowledge_pub_, scaledToOccupancy(r.knowledge, r.states != kUnknown));
  send(evaluation_pub_, scaledToOccupancy(r.evaluation, r.evaluation > 0));

  visualization_msgs::Marker sk;
  sk.header.frame_id = node_config_.frame_id;
  sk.header.stamp = ros::Time::now();
  sk.ns = "skeleton";
  sk.type = visualization_msgs::Marker::CUBE_LIST;
  sk.action = visualization_msgs::Marker::ADD;
  sk.pose.orientation.w = 1.0;
  sk.scale.x = sk.scale.y = r.geometry.resolution;
  sk.scale.z = 0.01;
  sk.color.b = 1.0f;
  sk.color.g = 0.5f;
  sk.color.a = 1.0f;
  for (int row = 0; row < r.skeleton.rows; ++row)
    for (int col = 0; col < r.skeleton.cols; ++col)
      if (r.skeleton.at<uint8_t>(row, col)) {
        geometry_msgs::Point p;
        const Eigen::Vector2d c = r.geometry.center({col, row});
        p.x = c.x();
        p.y = c.y();
        p.z = 0.01;
        sk.points.push_back(p);
      }
  skeleton_pub_.publish(sk);

  visualization_msgs::Marker lm = sk;
  lm.ns = "landmarks";
  lm.type = visualization_msgs::Marker::SPHERE_LIST;
  lm.scale.x = lm.scale.y = lm.scale.z = 0.12;
  lm.points.clear();
  for (size_t i = 1; i < r.cost_map.nodes.size(); ++i) {
    const Landmark& l = r.cost_map.nodes[i];
    geometry_msgs::Point p;
    p.x = r.geometry.origin_x + l.pos.x() * r.geometry.resolution;
    p.y = r.geometry.origin_y + l.pos.y() * r.geometry.resolution;
    p.z = 0.06;
    lm.points.push_back(p);
    std_msgs::ColorRGBA c;
    c.a = 1.0f;
    c.r = 1.0f;
    c.g = l.kind == Landmark::kAnchor ? 0.0f : (l.kind == Landmark::kSpecial ? 0.5f : 1.0f);
    c.b = l.kind == Landmark::kCoverage ? 1.0f : 0.0f;
    lm.colors.push_back(c);
  }
  landmarks_pub_.publish(lm);
}

void ExplorerNode::writeImages(const PlanResult& r) {
  if (node_config_.run_dir.empty()) return;
  char prefix[32];
  std::snprintf(prefix, sizeof(prefix), "step_%03u_", step_);
  try {
    // The configuration of this run (run_dir/config.yaml), with the first plan's files (not at start:
    // a run directory the mission refuses stays as it was): what plan_step --config and the
    // evaluation (mission_node's true coverage, floor_coverage --config) rebuild the floor map with.
    if (!config_written_) writeFileAtomic(node_config_.run_dir + "/config.yaml", config_text_);
    config_written_ = true;
    writePlanImages(r, node_config_.run_dir, prefix, node_config_.image_scale);
    writeFileAtomic(node_config_.run_dir + "/" + prefix + "plan.json", planToJson(r) + "\n");
    writeFileAtomic(node_config_.run_dir + "/" + prefix + "path.csv", pathToCsv(r));
    if (!r.states.empty()) {  // the latest floor grid, georeferenced (the run report's background)
      writeFileAtomic(node_config_.run_dir + "/floor_map.png", floorMapPng(r));
      writeFileAtomic(node_config_.run_dir + "/floor_map.yaml", floorMapYaml(r, "floor_map.png"));
    }
  } catch (const std::exception& e) {
    ROS_ERROR("explorer_node: cannot write the step images: %s", e.what());
  }
}

}  // namespace explorer
}  // namespace scanstop
