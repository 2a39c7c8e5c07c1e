#include "scanstop_slam/icp_slam.h"

#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/config.h"

namespace scanstop {
namespace slam {

void SlamConfig::validate() const {
  icp.validate();
  requireInRange("coarse_c_max", coarse_c_max_m, 0.0, 5.0, "m");
  requireInRange("source_voxel", source_voxel_m, 0.0, 1.0, "m");
  requireInRange("refine_t_c", refine_t_c_m, 0.0, 0.01, "m");
  requireInRange("refine_r_c", refine_r_c_rad, 1e-9, 0.01, "rad");
  requireInRange("refine_max_iterations", refine_max_iterations, 1, 10000);
  requireInRange("refine_source_voxel", refine_source_voxel_m, 0.0, 1.0, "m");
  requireInRange("refine_max_correction", refine_max_correction_m, 0.0, 10.0, "m");
  requireInRange("refine_max_correction_angle", refine_max_correction_rad, 0.0, M_PI, "rad");
  requireInRange("max_points_per_voxel", max_points_per_voxel, 1, 100000);
  requireInRange("map_spacing", map_spacing_m, 0.0, icp.c_max_m, "m");
  requireInRange("max_point_distance", max_point_distance_m, 0.1, 10000.0, "m");
  requireInRange("max_odom_jump", max_odom_jump_m, 0.01, 100000.0, "m");
}

std::string scanProblem(const PointCloud& scan_base, double max_point_distance_m) {
  if (scan_base.empty()) return "the cloud has no points";
  size_t finite = 0;
  for (size_t i = 0; i < scan_base.points.size(); ++i) {
    const Eigen::Vector3f& p = scan_base.points[i];
    if (p.hasNaN()) continue;  // NaN marks a beam without a return
    std::ostringstream where;
    where << "point " << i << " (" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    if (!p.allFinite()) return where.str() + " has an infinite coordinate";
    if (p.cast<double>().norm() > max_point_distance_m)
      return where.str() + " is " + std::to_string(p.norm()) + " m from base_link, beyond max_point_distance " +
             std::to_string(max_point_distance_m) + " m";
    ++finite;
  }
  if (finite == 0) return "the cloud has no finite point (all " + std::to_string(scan_base.size()) + " are NaN)";
  return "";
}

IcpSlam::IcpSlam(const SlamConfig& config, const std::string& map_dir)
    : config_(config), map_((config.validate(), config.icp.c_max_m), config.max_points_per_voxel, config.map_spacing_m) {
  if (map_dir.empty()) return;
  dir_ = std::make_unique<MapDirectory>(map_dir);
  for (const MapProblem& p : dir_->problems()) skipped_.push_back({p.path, p.problem});
  for (size_t i = 0; i < dir_->size(); ++i) {
    const MapScanInfo& info = dir_->scans()[i];
    // The pose is kept either way (the trajectory goes on from the last scan).
    last_map_ = info.map_pose;
    last_odom_ = info.odom_pose;
    PointCloud scan;
    try {
      scan = dir_->loadScan(i);
    } catch (const std::exception& e) {
      skipped_.push_back({dir_->dir() + "/" + info.file, e.what()});
      continue;
    }
    const std::string problem = scanProblem(scan, config_.max_point_distance_m);
    if (!problem.empty()) {
      skipped_.push_back({dir_->dir() + "/" + info.file, "scan " + std::to_string(info.index) + ": " + problem});
      continue;
    }
    const Eigen::Vector3f origin = info.map_pose.toIsometry3f() * info.sensor_origin.cast<float>();
    map_.add(transformCloud(scan, info.map_pose.toIsometry3f()).points, &origin);
  }
  count_ = static_cast<size_t>(dir_->nextIndex());
}

std::string IcpSlam::odomProblem(const Pose2D& odom_pose) const {
  if (!std::isfinite(odom_pose.x) || !std::isfinite(odom_pose.y) || !std::isfinite(odom_pose.yaw))
    return "the odometry pose " + odom_pose.toString() + " is not finite";
  if (count_ == 0) return "";
  const double jump = std::hypot(odom_pose.x - last_odom_.x, odom_pose.y - last_odom_.y);
  if (jump > config_.max_odom_jump_m)
    return "the odometry pose " + odom_pose.toString() + " is " + std::to_string(jump) +
           " m from the last scan's " + last_odom_.toString() + ", beyond max_odom_jump " +
           std::to_string(config_.max_odom_jump_m) + " m (an odometry reset or a corrupt pose)";
  return "";
}

std::vector<Eigen::Vector3f> IcpSlam::coarseSource(const std::vector<Eigen::Vector3f>& source) const {
  // A sparser subset is plenty for the coarse stage and keeps its wider search cheap.
  return voxelDownsample(source, std::max(config_.source_voxel_m, 0.05));
}

std::vector<Eigen::Vector3f> IcpSlam::refineSource(const std::vector<Eigen::Vector3f>& source) const {
  return config_.refine_source_voxel_m > config_.source_voxel_m ? voxelDownsample(source, config_.refine_source_voxel_m)
                                                                 : source;
}

Registration IcpSlam::registerScan(const PointCloud& scan_base, const Pose2D& odom_pose,
                                   const Eigen::Vector3d& sensor_origin, double stamp_s) {
  const auto start = std::chrono::steady_clock::now();
  // Every check before anything changes: a refused scan leaves the map, the directory and the poses as they were.
  std::string problem = scanProblem(scan_base, config_.max_point_distance_m);
  if (problem.empty()) problem = odomProblem(odom_pose);
  if (problem.empty() && !sensor_origin.allFinite()) problem = "the sensor origin is not finite";
  if (problem.empty() && !std::isfinite(stamp_s)) problem = "the stamp is not finite";
  if (!problem.empty()) throw std::invalid_argument(problem);
  Registration r;
  r.index = static_cast<uint32_t>(dir_ ? static_cast<size_t>(dir_->nextIndex()) : count_);
  // Initial guess: the last corrected pose composed with the odometry delta since then. The first
  // scan defines the map: map = odom at the first scan.
  r.guess = count_ == 0 ? odom_pose : last_map_ * last_odom_.between(odom_pose);
  const std::vector<Eigen::Vector3f> source = voxelDownsample(scan_base.points, config_.source_voxel_m);
  const Eigen::Vector3f origin = sensor_origin.cast<float>();
  if (map_.size() == 0) {  // the first scan (or every earlier one was skipped) defines the map
    r.map_pose = r.guess;
    r.converged = true;
  } else {
    Eigen::Isometry3d start = r.guess.toIsometry3d();
    int coarse_iterations = 0;
    if (config_.coarse_c_max_m > config_.icp.c_max_m) {
      // The coarse stage only moves the start; its own checks use the coarse distance.
      IcpConfig coarse = config_.icp;
      coarse.c_max_m = config_.coarse_c_max_m;
      coarse.t_c_m = std::max(coarse.t_c_m, 0.002);
      coarse.r_c_rad = std::max(coarse.r_c_rad, 0.1 * M_PI / 180.0);
      const IcpResult c = icp(map_, coarseSource(source), start, coarse, &origin);
      coarse_iterations = c.iterations;
      if (c.converged) start = c.T_target_source;
    }
    IcpResult icp_result = icp(map_, source, start, config_.icp, &origin);
    icp_result.iterations += coarse_iterations;
    if (icp_result.converged && config_.refine_t_c_m > 0.0) {
      IcpConfig refine = config_.icp;
      refine.unique_matches = true;
      refine.t_c_m = config_.refine_t_c_m;
      refine.r_c_rad = config_.refine_r_c_rad;
      refine.max_iterations = config_.refine_max_iterations;
      IcpResult refined = icp(map_, refineSource(source), icp_result.T_target_source, refine, &origin);
      // Not settled within its iterations, or moved farther than a bias can be: the thesis stage's
      // result stands.
      const Eigen::Isometry3d moved = icp_result.T_target_source.inverse() * refined.T_target_source;
      r.refine_moved_m = moved.translation().norm();
      r.refine_moved_rad = Eigen::AngleAxisd(moved.linear()).angle();
      if (refined.converged &&
          (r.refine_moved_m > config_.refine_max_correction_m || r.refine_moved_rad > config_.refine_max_correction_rad)) {
        r.refine_rejected = true;
        refined.converged = false;
      }
      if (refined.converged) {
        refined.iterations += icp_result.iterations;
        icp_result = refined;
      } else {
        icp_result.iterations += refined.iterations;
      }
    }
    if (icp_result.converged) {
      // The bound on the correction applies to the whole correction of the odometry guess.
      const Eigen::Isometry3d correction = r.guess.toIsometry3d().inverse() * icp_result.T_target_source;
      if (correction.translation().norm() > config_.icp.max_correction_m ||
          Eigen::AngleAxisd(correction.linear()).angle() > config_.icp.max_correction_rad) {
        icp_result.converged = false;
        icp_result.failure = "the correction of the odometry guess (" + std::to_string(correction.translation().norm()) +
                             " m) exceeds max_correction";
      }
    }
    r.converged = icp_result.converged;
    r.failure = icp_result.failure;
    r.iterations = icp_result.iterations;
    r.correspondences = icp_result.correspondences;
    r.rms_m = icp_result.rms_m;
    r.overlap = icp_result.overlap;
    r.condition = icp_result.condition;
    r.degenerate = icp_result.degenerate;
    r.weak_direction = icp_result.weak_direction;
    r.remapped = icp_result.remapped;
    r.map_pose = r.converged ? Pose2D::fromIsometry3d(icp_result.T_target_source) : r.guess;
  }
  // The whole scan (not only the matching subset) joins the map.
  const Eigen::Isometry3f T_map_base = r.map_pose.toIsometry3f();
  std::vector<Eigen::Vector3f> in_map;
  in_map.reserve(scan_base.points.size());
  for (const auto& p : scan_base.points)
    if (p.allFinite()) in_map.push_back(T_map_base * p);
  if (dir_) {
    MapScanInfo info;
    info.index = r.index;
    info.stamp_s = stamp_s;
    info.map_pose = r.map_pose;
    info.odom_pose = odom_pose;
    info.sensor_origin = sensor_origin;
    info.converged = r.converged;
    info.iterations = static_cast<uint32_t>(r.iterations);
    info.correspondences = static_cast<uint32_t>(r.correspondences);
    info.rms_m = r.rms_m;
    info.overlap = r.overlap;
    dir_->append(info, scan_base);  // throws before the in-memory map changes: nothing half-applied
  }
  const Eigen::Vector3f origin_map = T_map_base * sensor_origin.cast<float>();
  map_.add(in_map, &origin_map);
  last_map_ = r.map_pose;
  last_odom_ = odom_pose;
  count_ = dir_ ? static_cast<size_t>(dir_->nextIndex()) : count_ + 1;
  r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace slam
}  // namespace scanstop
