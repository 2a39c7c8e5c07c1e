#pragma once
/// The mission's persistent state: everything needed to resume a mission after any node dies and to
/// write its report. Saved atomically to <run_dir>/mission_state.yaml after every step.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/pose.h"
#include "scanstop_mission/robot_system.h"

namespace scanstop {
namespace mission {

/// Mission states as published on mission/status.
enum class State { Idle, Scanning, Registering, Planning, Driving, Paused, Meshing, Done, Aborted, Failed };
const char* toString(State s);
State stateFromString(const std::string& s);  ///< throws std::invalid_argument

/// One scan of the mission.
struct ScanRecord {
  int index = 0;    ///< SLAM's scan index
  Pose2D map_pose;  ///< corrected pose (map): SLAM's latest, as finally optimized
  /// The pose the registration answered, when SLAM has moved the scan since (pose-graph relaxation);
  /// nullopt while map_pose is still that pose.
  std::optional<Pose2D> registered_pose;
  Pose2D odom_pose;                 ///< odometry pose at scan time (odom = map at the start)
  std::optional<Pose2D> true_pose;  ///< ground truth in the map frame (simulation)
  bool converged = true;
  double rms_m = 0.0;
  uint32_t valid_points = 0;
  double scan_time_s = 0.0;      ///< modelled scan duration [s]
  double register_wall_s = 0.0;  ///< registration compute time [s]
  double plan_wall_s = 0.0;      ///< planning compute time of the cycle that led here [s]
  double coverage = 0.0;         ///< coverage reported by the plan after this scan
  /// Modelled mission time when that coverage was known (after the plan that followed the scan) [s].
  double mission_time_s = 0.0;
};

/// One event worth keeping (collisions, failures, replans).
struct EventRecord {
  double elapsed_s = 0.0;
  std::string what;
};

struct MissionState {
  State state = State::Idle;
  std::vector<ScanRecord> scans;
  std::vector<Eigen::Vector2d> unreachable;  ///< targets the robot failed to reach (map frame)
  std::vector<Contact> contacts;             ///< where the robot touched something (map frame): obstacles
  /// Where the leg check stopped a leg before an obstruction the latest scan showed (map frame; the
  /// point that stopped it): obstacles for every later plan like the contacts, but no contact (they
  /// do not count towards max_contacts). The explorer's floor map may not hold them (sparse points
  /// it takes for speckle), and without them every later plan may lead through the same spot.
  std::vector<Contact> obstructions;
  // True clearance of the body (simulation): over every motion with a measurement.
  int clearance_motions = 0;      ///< motions with a true clearance
  int clearance_legs = 0;         ///< ... of them straight legs (forward motions)
  int close_legs = 0;             ///< legs that came closer than 5 cm (contacts included)
  double min_clearance_m = -1.0;  ///< smallest true clearance of any motion [m]; < 0: none measured
  std::vector<EventRecord> events;
  int collisions = 0;
  int plans = 0;
  double coverage = 0.0;
  bool complete = false;
  std::string complete_reason;
  std::string last_error;
  double elapsed_s = 0.0;        ///< wall time spent in the mission so far [s]
  double modelled_time_s = 0.0;  ///< sum of the steps' modelled durations [s]
  // modelled_time_s split: scanning, driving (every motion) and compute (registration and planning,
  // as the serving nodes measured them).
  double modelled_scan_s = 0.0;
  double modelled_drive_s = 0.0;
  double modelled_compute_s = 0.0;
  std::string world;  ///< world name (simulation) for the report
  // The pose estimate: map pose = last_map_pose * odom_at_last_scan^-1 * odom_now.
  Pose2D last_map_pose;      ///< corrected pose of the last registered scan (map)
  Pose2D odom_at_last_scan;  ///< odometry pose of the last registered scan
  Pose2D odom_now;           ///< odometry pose after the last step
  // The path being driven, so that a restarted mission drives on along it instead of replanning.
  std::vector<Eigen::Vector2d> path;                      ///< waypoints of the current plan (map frame); empty: none
  std::vector<bool> path_scan_at;                         ///< the plan's scan flags, one per waypoint
  Eigen::Vector2d path_target = Eigen::Vector2d::Zero();  ///< the current plan's target
  int path_next = 0;                                      ///< index of the waypoint being driven to
  int path_scan_mark = -1;  ///< scans.size() when the scan at path_next began; -1: none yet

  /// The current pose estimate in the map frame.
  Pose2D estimate() const { return last_map_pose * odom_at_last_scan.inverse() * odom_now; }

  /// Writes the state as YAML, atomically (temporary file, fsync, rename). Throws IoError.
  void save(const std::string& path) const;
  /// Reads a saved state; throws IoError naming the file and the problem when it is corrupt.
  static MissionState load(const std::string& path);
};

}  // namespace mission
}  // namespace scanstop
