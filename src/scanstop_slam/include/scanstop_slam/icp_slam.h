#pragma once
/// ICP SLAM (thesis 4.2/4.3): every new scan is registered against all earlier scans (the whole
/// map in one persistent voxel index), starting from the last corrected pose composed with the
/// odometry delta since then. A failed registration keeps the odometry-based pose and is flagged.
/// The map is written to a map directory after every scan and can be loaded back.

#include <memory>
#include <string>

#include "scanstop_common/cloud.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_slam/icp.h"

namespace scanstop {
namespace slam {

struct SlamConfig {
  IcpConfig icp;
  /// Coarse-to-fine: first ICP with this correspondence distance (odometry can be off by more than
  /// c_max after a long leg: 20 cm and 3 deg are common), then the thesis' c_max from there.
  /// <= c_max: a single stage.
  double coarse_c_max_m = 0.3;
  double source_voxel_m = 0.02;   ///< scan points used for matching: one per voxel of this size (0 = all) [m]
  int max_points_per_voxel = 30;  ///< map points kept per c_max voxel (bounds memory and query time)
  double map_spacing_m = 0.0;     ///< a map point joins only if none of its voxel is closer [m] (0 = first come)
  void validate() const;
};

/// One registered scan.
struct Registration {
  uint32_t index = 0;
  Pose2D map_pose;            ///< corrected pose of base_link in the map frame
  Pose2D guess;               ///< the initial guess from odometry
  bool converged = false;
  std::string failure;        ///< why the registration failed (empty when it converged)
  int iterations = 0;
  size_t correspondences = 0;
  double rms_m = 0.0;
  double overlap = 0.0;
  double time_s = 0.0;        ///< compute time [s]
};

class IcpSlam {
 public:
  /// map_dir may be empty (nothing persisted); otherwise its scans are loaded (resume).
  /// Throws IoError naming a corrupt file.
  IcpSlam(const SlamConfig& config, const std::string& map_dir = "");

  /// Registers a scan given in base_link (NaN points ignored) taken at odom_pose; sensor_origin
  /// (scanner centre in base_link) and stamp are stored with it.
  Registration registerScan(const PointCloud& scan_base, const Pose2D& odom_pose,
                            const Eigen::Vector3d& sensor_origin = Eigen::Vector3d::Zero(), double stamp_s = 0.0);

  size_t scanCount() const { return count_; }
  const VoxelMap& map() const { return map_; }
  const Pose2D& lastMapPose() const { return last_map_; }
  const Pose2D& lastOdomPose() const { return last_odom_; }
  /// T_map_odom: maps odometry poses into the map frame.
  Pose2D mapFromOdom() const { return last_map_ * last_odom_.inverse(); }
  /// The map directory (null when not persisting).
  const MapDirectory* mapDirectory() const { return dir_.get(); }

 private:
  std::vector<Eigen::Vector3f> coarseSource(const std::vector<Eigen::Vector3f>& source) const;
  SlamConfig config_;
  VoxelMap map_;
  std::unique_ptr<MapDirectory> dir_;
  size_t count_ = 0;
  Pose2D last_map_, last_odom_;
};

}  // namespace slam
}  // namespace scanstop
