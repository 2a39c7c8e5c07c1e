#pragma once
/// Ground truth for mission_node's report and the offline SLAM tools (icp_replay, relax_bench): the true pose of every
/// scan as mission_node writes it in simulation (mission_state.yaml, `scans: [{index, true_pose: [x, y, yaw]}, ...]`),
/// and the pose error of a trajectory against it. Evaluation, not SLAM: the core (scanstop_slam_core) never sees it.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/pose.h"

namespace scanstop {
namespace eval {

/// True poses by scan index (a scan the mission adopted after a crash may have none). Throws
/// IoError naming the file (and the scan entry) for a missing or unreadable file, YAML that is not
/// a mission state, a bad index or a pose that is not finite or beyond 10 km.
std::vector<std::optional<Pose2D>> readTruth(const std::string& path);

/// Pose error over the scans that have a true pose (ATE, no alignment: both trajectories start in
/// the same frame).
struct TrajectoryError {
  size_t scans = 0;    ///< scans with a true pose
  double rms_m = 0.0;  ///< position RMS [m]
  double max_m = 0.0;  ///< largest position error [m]
  size_t max_at = 0;   ///< position (in the input order) of the largest error
  double yaw_rms_deg = 0.0;
  double yaw_max_deg = 0.0;
};
/// poses[i] against truth[i] (nullopt: no truth, skipped); the two must have the same size.
TrajectoryError trajectoryError(const std::vector<Pose2D>& poses, const std::vector<std::optional<Pose2D>>& truth);

/// How wrong one relative pose measurement (a pose graph edge: node `to` in node `from`'s frame) is
/// against the true poses of its two nodes, with the residual exactly as PoseGraph counts it
/// (pose_graph.h): e = [R(yaw_from)^T (t_to - t_from) - t_z; yaw_to - yaw_from - yaw_z].
struct MeasurementError {
  Eigen::Vector3d residual = Eigen::Vector3d::Zero();  ///< e at the true poses [m, m, rad]
  double position_m = 0.0;                             ///< |e.xy| [m]
  double yaw_deg = 0.0;                                ///< |e.yaw| [deg]
  /// sqrt(e^T information e): how many of its own standard deviations the measurement is off
  /// (about 1 for an honest information matrix; far more: overconfident) [1]
  double whitened = 0.0;
};
MeasurementError measurementError(const Pose2D& true_from, const Pose2D& true_to, const Pose2D& measured,
                                  const Eigen::Matrix3d& information);

}  // namespace eval
}  // namespace scanstop
