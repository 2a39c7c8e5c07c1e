#include "scanstop_explorer/explorer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "scanstop_common/config.h"

namespace scanstop {
namespace explorer {

void ExplorerConfig::validate() const {
  floor.validate();
  planner.validate();
  requireInRange("known_free_radius_m", known_free_radius_m, 0.0, 5.0, "m");
  requireInRange("self_filter_radius_m", self_filter_radius_m, 0.0, 5.0, "m");
  requireInRange("target_tolerance_m", target_tolerance_m, 1e-6, 10.0, "m");
  requireInRange("progress_m", progress_m, 0.0, 10.0, "m");
  requireInRange("max_failed_attempts", max_failed_attempts, 1, 100);
  requireInRange("blacklist_radius_m", blacklist_radius_m, 1e-6, 10.0, "m");
  requireInRange("contact_radius_m", contact_radius_m, 1e-6, 2.0, "m");
}

Explorer::Explorer(const ExplorerConfig& config) : config_(config), floor_(config.floor) { config_.validate(); }

bool Explorer::addScan(uint32_t index, const Pose2D& T_map_base, const std::vector<Eigen::Vector3f>& points_map) {
  if (scans_.count(index)) return false;
  Scan scan;
  scan.pose = T_map_base;
  const Eigen::Vector2f center(static_cast<float>(T_map_base.x), static_cast<float>(T_map_base.y));
  const float r2 = static_cast<float>(config_.self_filter_radius_m * config_.self_filter_radius_m);
  // Only the floor and obstacle layers matter to the grid (FloorMap::addPoints); the ceiling and
  // walls above the robot are not kept.
  const float lo_z = static_cast<float>(-0.5 * config_.floor.floor_layer_m);
  const float hi_z = static_cast<float>(0.5 * config_.floor.floor_layer_m + config_.floor.robot_height_m);
  const Eigen::Matrix2f R = Eigen::Rotation2Df(static_cast<float>(T_map_base.yaw)).toRotationMatrix();
  scan.points_base.reserve(points_map.size() / 2);
  for (const Eigen::Vector3f& p : points_map) {
    if (!p.allFinite() || p.z() < lo_z || p.z() > hi_z) continue;
    const Eigen::Vector2f d = p.head<2>() - center;
    if (d.squaredNorm() < r2) continue;
    const Eigen::Vector2f b = R.transpose() * d;
    scan.points_base.emplace_back(b.x(), b.y(), p.z());
  }
  scan.points_base.shrink_to_fit();
  addToFloor(scan);
  scans_.emplace(index, std::move(scan));
  return true;
}

void Explorer::addToFloor(const Scan& scan) {
  const Pose2D& T = scan.pose;
  const Eigen::Matrix2f R = Eigen::Rotation2Df(static_cast<float>(T.yaw)).toRotationMatrix();
  const Eigen::Vector2f t(static_cast<float>(T.x), static_cast<float>(T.y));
  std::vector<Eigen::Vector3f> points_map;
  points_map.reserve(scan.points_base.size());
  for (const Eigen::Vector3f& b : scan.points_base) {
    const Eigen::Vector2f m = R * b.head<2>() + t;
    points_map.emplace_back(m.x(), m.y(), b.z());
  }
  floor_.addPoints(points_map);
  floor_.addKnownFree(Eigen::Vector2d(T.x, T.y), config_.known_free_radius_m);
}

size_t Explorer::updatePoses(const std::map<uint32_t, Pose2D>& poses, double tol_m, double tol_rad) {
  size_t moved = 0;
  for (const auto& p : poses) {
    const auto it = scans_.find(p.first);
    if (it == scans_.end()) continue;
    const Pose2D& a = it->second.pose;
    const Pose2D& b = p.second;
    if (!std::isfinite(b.x) || !std::isfinite(b.y) || !std::isfinite(b.yaw)) continue;
    const double dyaw = std::abs(std::remainder(a.yaw - b.yaw, 2 * M_PI));
    if (std::hypot(a.x - b.x, a.y - b.y) > tol_m || dyaw > tol_rad) ++moved;
  }
  if (moved == 0) return 0;
  for (const auto& p : poses) {
    const auto it = scans_.find(p.first);
    if (it != scans_.end() && std::isfinite(p.second.x) && std::isfinite(p.second.y) && std::isfinite(p.second.yaw))
      it->second.pose = p.second;
  }
  // The evidence is rebuilt in index order, as if every scan had been added at its new pose.
  floor_ = FloorMap(config_.floor);
  for (const auto& s : scans_) addToFloor(s.second);
  return moved;
}

size_t Explorer::loadMapDirectory(const MapDirectory& dir, std::vector<std::string>* problems, size_t* moved) {
  size_t added = 0;
  if (problems)
    for (const MapProblem& p : dir.problems()) problems->push_back(p.message());
  std::map<uint32_t, Pose2D> known;
  for (size_t i = 0; i < dir.size(); ++i) {
    const MapScanInfo& info = dir.scans()[i];
    if (hasScan(info.index)) {
      known[info.index] = info.map_pose;
      continue;
    }
    PointCloud cloud;
    try {
      cloud = dir.loadScanInMap(i);
    } catch (const std::exception& e) {
      if (problems) problems->push_back("scan " + std::to_string(info.index) + " not loaded: " + e.what());
      continue;
    }
    added += addScan(info.index, info.map_pose, cloud.points) ? 1 : 0;
  }
  const size_t n_moved = updatePoses(known);
  if (moved) *moved = n_moved;
  return added;
}

std::vector<Eigen::Vector2d> Explorer::scanPositions() const {
  std::vector<Eigen::Vector2d> out;
  for (const auto& s : scans_) out.emplace_back(s.second.pose.x, s.second.pose.y);
  return out;
}

void Explorer::blacklist(const Eigen::Vector2d& center_map, double radius_m) {
  blacklist_.emplace_back(center_map, radius_m);
}

bool Explorer::addContact(const Eigen::Vector2d& point_map, double radius_m) {
  if (!point_map.allFinite() || !std::isfinite(radius_m) || radius_m < 0.0) return false;
  for (const auto& c : contacts_)
    if ((c.first - point_map).norm() < 0.01) return false;
  contacts_.emplace_back(point_map, radius_m > 0.0 ? radius_m : config_.contact_radius_m);
  return true;
}

bool Explorer::markUnreachable(const Eigen::Vector2d& target_map) {
  if (!target_map.allFinite()) return false;
  for (const auto& b : blacklist_)
    if ((b.first - target_map).norm() < 1e-3) return false;
  blacklist_.emplace_back(target_map, config_.blacklist_radius_m);
  if (last_.active && (last_.target - target_map).norm() <= config_.blacklist_radius_m) last_.active = false;
  return true;
}

PlanResult Explorer::plan(const Pose2D& T_map_base, const std::optional<Eigen::Vector2d>& goal) {
  const auto t0 = std::chrono::steady_clock::now();
  PlanInput input;
  input.states = floor_.states();
  input.geometry = floor_.geometry();
  // Contacts: obstacles whatever the scans show (what the robot touched was not seen well).
  for (const auto& [c, radius] : contacts_) {
    const cv::Point cell = input.geometry.cellOf(c.x(), c.y());
    const int r = std::max(1, static_cast<int>(std::lround(radius / input.geometry.resolution)));
    if (!input.states.empty()) cv::circle(input.states, cell, r, cv::Scalar(kObstacle), cv::FILLED);
  }
  input.scan_positions = scanPositions();
  input.robot = T_map_base;
  const double floor_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  PlanResult res = computeMaps(input, config_.planner);
  res.timings_ms.insert(res.timings_ms.begin(), {"floor", floor_ms});
  if (!res.success) return res;

  // Did the robot reach, or at least get closer to, the target of the previous plan?
  const Eigen::Vector2d robot(T_map_base.x, T_map_base.y);
  std::string note;
  input.goal = goal;
  if (goal) last_.active = false;  // returning, not exploring: no attempts to count
  if (last_.active) {
    if ((robot - last_.target).norm() <= config_.target_tolerance_m) {
      last_.active = false;
    } else {
      const cv::Point cell = res.geometry.cellOf(last_.target.x(), last_.target.y());
      double cost_now = std::numeric_limits<double>::infinity();
      if (res.geometry.contains(cell)) cost_now = res.cost_map.cost.at<float>(cell) * res.geometry.resolution;
      if (!(cost_now < last_.cost_m - config_.progress_m)) ++last_.failures;
      if (std::isfinite(cost_now)) last_.cost_m = cost_now;
      if (last_.failures >= config_.max_failed_attempts) {
        blacklist_.emplace_back(last_.target, config_.blacklist_radius_m);
        note = "; blacklisted the unreachable target (" + std::to_string(last_.target.x()) + ", " +
               std::to_string(last_.target.y()) + ") after " + std::to_string(last_.failures) +
               " plans without progress";
        last_.active = false;
      }
    }
  }
  input.blacklist = blacklist_;
  choosePlan(res, input, config_.planner);
  res.message += note;
  if (res.complete || res.target_cell.x < 0 || goal) {
    last_.active = false;
  } else if (last_.active && (res.target - last_.target).norm() <= config_.blacklist_radius_m) {
    last_.target = res.target;  // the same target area again: keep counting
  } else {
    last_ = Attempt{true, res.target, res.target_cost_m, 0};
  }
  return res;
}

}  // namespace explorer
}  // namespace scanstop
