#pragma once
/// The steps the mission sequences, as a ROS-free interface: mission_node implements it with service
/// calls (timeouts, bounded retries), the tests with an in-memory world.

#include <Eigen/Core>
#include <any>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/pose.h"

namespace scanstop {
namespace mission {

/// What every step answers: success, a reason a user can act on, and the step's modelled duration.
struct StepResult {
  bool success = false;
  std::string message;
  double duration_s = 0.0;   ///< as reported by the serving node (modelled time in simulation) [s]
  double wall_time_s = 0.0;  ///< wall-clock time the call took, measured by the caller [s]
};

/// Where the robot touched something the map did not show (map frame): an obstacle disc for every
/// later plan.
struct Contact {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();  ///< [m]
  /// Radius of the obstacle disc [m]; 0: the explorer's own contact_radius_m (a contact whose place
  /// is only guessed, ahead of the robot).
  double radius_m = 0.0;
};

/// A 3D scan taken while the robot stands still.
struct ScanResult : StepResult {
  Pose2D odom_pose;  ///< odometry pose of base_link at scan time (odom frame)
  uint32_t raw_points = 0;
  uint32_t valid_points = 0;
  uint32_t planes_dropped = 0;
  std::any payload;  ///< the cloud as the implementation keeps it (handed back to registerScan)
  /// The scan's finite points in base_link [m] (for the safety check of the legs driven before the
  /// next scan); may be empty (no check).
  std::vector<Eigen::Vector3f> points_base;
};

/// A relative motion, as measured by odometry.
struct MotionResult : StepResult {
  double achieved = 0.0;   ///< [rad] for a rotation, [m] for a forward motion
  Pose2D odom_pose;        ///< final odometry pose of base_link
  bool collision = false;  ///< stopped by a collision or stall
  /// Simulation only: the true smallest distance between the body and the world along the motion
  /// (sim_node's ground_truth/clearance) [m]; nullopt on a real robot.
  std::optional<double> true_clearance_m;
};

/// A scan registered into the map.
struct RegisterResult : StepResult {
  Pose2D map_pose;  ///< corrected pose of base_link in the map frame
  bool converged = false;
  uint32_t iterations = 0;
  uint32_t correspondences = 0;
  double rms_m = 0.0;
  uint32_t scan_index = 0;
};

/// The explorer's answer: a path of straight segments to the next scan location.
struct PlanResult : StepResult {
  std::vector<Eigen::Vector2d> waypoints;  ///< map frame [m], from the robot to the target
  std::vector<bool> scan_at;               ///< one flag per waypoint
  /// Per waypoint: the map's clearance of the leg ending there [m] (PlanNext.clearance); empty: unknown.
  std::vector<double> clearance_m;
  Eigen::Vector2d target = Eigen::Vector2d::Zero();
  double score = 0.0;
  bool complete = false;  ///< exploration is complete
  std::string complete_reason;
  double coverage = 0.0;  ///< observed share of the reachable floor [0..1]
  double d_max_m = 0.0;   ///< the explorer's d_max: the longest straight motion [m]; 0: not said
};

/// A reconstructed surface mesh.
struct MeshResult : StepResult {
  bool available = false;  ///< false: no mesher is running (not an error)
  uint32_t triangles = 0;
  std::string file;
};

/// The robot, the SLAM node, the explorer and the mesher as the mission sees them.
class RobotSystem {
 public:
  virtual ~RobotSystem() = default;
  virtual ScanResult takeScan(int planes) = 0;
  virtual RegisterResult registerScan(const ScanResult& scan) = 0;
  virtual MotionResult rotate(double angle_rad) = 0;
  virtual MotionResult forward(double distance_m) = 0;
  /// The next scan location and the path to it; with a goal, the path to the reachable cell nearest
  /// to the goal instead (PlanResult::complete still says whether exploration is complete).
  /// `contacts`: where the robot touched something (map frame): obstacles the plan must not pass.
  virtual PlanResult planNext(const Pose2D& map_pose, const std::vector<Eigen::Vector2d>& unreachable,
                              const std::vector<Contact>& contacts, const std::optional<Eigen::Vector2d>& goal) = 0;
  virtual MeshResult buildMesh(const std::string& output_path) = 0;
  /// The true pose in the map frame (simulation only), for the report; nullopt on a real robot.
  virtual std::optional<Pose2D> groundTruth() = 0;
  /// Number of scans the SLAM map (map directory) holds now, to reconcile after a lost response;
  /// -1 when unknown.
  virtual int registeredScanCount() = 0;
  /// The pose SLAM stored for scan `index` (after a lost response); nullopt when unknown.
  virtual std::optional<Pose2D> registeredScanPose(int index) = 0;
  /// Every pose SLAM holds now, by scan index (after a relaxation of the pose graph they differ from
  /// the poses the registrations answered); empty when unknown. The default asks
  /// registeredScanPose() for each index below registeredScanCount().
  virtual std::vector<std::pair<int, Pose2D>> registeredScanPoses() {
    std::vector<std::pair<int, Pose2D>> out;
    const int count = registeredScanCount();
    for (int i = 0; i < count; ++i)
      if (const std::optional<Pose2D> p = registeredScanPose(i)) out.emplace_back(i, *p);
    return out;
  }
  /// The odometry pose SLAM stored with scan `index`; nullopt when unknown (the caller then assumes
  /// the robot has not moved since).
  virtual std::optional<Pose2D> registeredScanOdometry(int /*index*/) { return std::nullopt; }
  /// The base's odometry pose now (after a restart of the mission, which may have died while a
  /// motion it had asked for was carried out); nullopt when unknown.
  virtual std::optional<Pose2D> currentOdometry() { return std::nullopt; }
};

}  // namespace mission
}  // namespace scanstop
