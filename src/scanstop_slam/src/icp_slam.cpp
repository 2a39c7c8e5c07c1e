#include "scanstop_slam/icp_slam.h"

#include <chrono>

#include "scanstop_common/config.h"

namespace scanstop {
namespace slam {

void SlamConfig::validate() const {
  icp.validate();
  requireInRange("coarse_c_max", coarse_c_max_m, 0.0, 5.0, "m");
  requireInRange("source_voxel", source_voxel_m, 0.0, 1.0, "m");
  requireInRange("max_points_per_voxel", max_points_per_voxel, 1, 100000);
  requireInRange("map_spacing", map_spacing_m, 0.0, icp.c_max_m, "m");
}

IcpSlam::IcpSlam(const SlamConfig& config, const std::string& map_dir)
    : config_(config), map_((config.validate(), config.icp.c_max_m), config.max_points_per_voxel, config.map_spacing_m) {
  if (map_dir.empty()) return;
  dir_ = std::make_unique<MapDirectory>(map_dir);
  for (size_t i = 0; i < dir_->size(); ++i) {
    map_.add(dir_->loadScanInMap(i).points);
    last_map_ = dir_->scans()[i].map_pose;
    last_odom_ = dir_->scans()[i].odom_pose;
  }
  count_ = dir_->size();
}

std::vector<Eigen::Vector3f> IcpSlam::coarseSource(const std::vector<Eigen::Vector3f>& source) const {
  // A sparser subset is plenty for the coarse stage and keeps its wider search cheap.
  return voxelDownsample(source, std::max(config_.source_voxel_m, 0.05));
}

Registration IcpSlam::registerScan(const PointCloud& scan_base, const Pose2D& odom_pose,
                                   const Eigen::Vector3d& sensor_origin, double stamp_s) {
  const auto start = std::chrono::steady_clock::now();
  Registration r;
  r.index = static_cast<uint32_t>(count_);
  // Initial guess: the last corrected pose composed with the odometry delta since then. The first
  // scan defines the map: map = odom at the first scan.
  r.guess = count_ == 0 ? odom_pose : last_map_ * last_odom_.between(odom_pose);
  const std::vector<Eigen::Vector3f> source = voxelDownsample(scan_base.points, config_.source_voxel_m);
  if (count_ == 0) {
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
      const IcpResult c = icp(map_, coarseSource(source), start, coarse);
      coarse_iterations = c.iterations;
      if (c.converged) start = c.T_target_source;
    }
    IcpResult icp_result = icp(map_, source, start, config_.icp);
    icp_result.iterations += coarse_iterations;
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
  map_.add(in_map);
  last_map_ = r.map_pose;
  last_odom_ = odom_pose;
  ++count_;
  r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace slam
}  // namespace scanstop
