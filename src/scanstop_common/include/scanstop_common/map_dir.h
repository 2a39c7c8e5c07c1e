#pragma once
/// The map directory: the SLAM map on disk, shared by icp_slam_node (writes it after every scan),
/// the explorer, the mesher, the mission and the offline tools (read it).
///
/// Layout:
///   <dir>/poses.csv            one line per scan (header line first), rewritten atomically per scan
///   <dir>/scans/scan_NNNN.pcd  the scan's finite points in the base_link frame at scan time [m]
/// A scan's points in the map frame are map_pose.toIsometry3f() * p.

#include <cstdint>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"

namespace scanstop {

/// One scan's entry in poses.csv.
struct MapScanInfo {
  uint32_t index = 0;
  std::string file;                  ///< relative to the map directory, e.g. "scans/scan_0003.pcd"
  double stamp_s = 0.0;              ///< scan time [s]
  Pose2D map_pose;                   ///< corrected pose of base_link in the map frame
  Pose2D odom_pose;                  ///< odometry pose of base_link in the odom frame
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();  ///< scanner centre in base_link [m]
  bool converged = true;             ///< false: registration failed, the odometry-based pose was kept
  uint32_t iterations = 0;
  uint32_t correspondences = 0;
  double rms_m = 0.0;
  double overlap = 0.0;
};

/// Reads and appends to a map directory. Files are written atomically; loading validates each line
/// and each scan file and reports problems by file name.
class MapDirectory {
 public:
  /// Opens (creating it when missing) the directory; loads an existing poses.csv.
  /// Throws IoError naming the file and line when poses.csv is corrupt.
  explicit MapDirectory(const std::string& dir);

  const std::string& dir() const { return dir_; }
  const std::vector<MapScanInfo>& scans() const { return scans_; }
  size_t size() const { return scans_.size(); }

  /// Writes the cloud (base_link frame; NaN points dropped) as scans/scan_NNNN.pcd, then poses.csv.
  /// info.index must equal size(); info.file is filled in. Throws IoError.
  void append(MapScanInfo info, const PointCloud& cloud_base);
  /// Replaces the poses of existing scans (e.g. after a re-registration) and rewrites poses.csv.
  void updateInfo(const MapScanInfo& info);

  /// Loads scan i in the base_link frame. Throws IoError naming the file.
  PointCloud loadScan(size_t i) const;
  /// Loads scan i transformed into the map frame.
  PointCloud loadScanInMap(size_t i) const;

  /// Absolute path of poses.csv.
  std::string posesPath() const { return dir_ + "/poses.csv"; }

 private:
  void writePoses() const;
  std::string dir_;
  std::vector<MapScanInfo> scans_;
};

/// Transforms every point of a cloud (NaN stays NaN).
PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3f& T_target_source);

}  // namespace scanstop
