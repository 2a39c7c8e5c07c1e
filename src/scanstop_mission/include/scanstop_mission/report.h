#pragma once
/// The run report: summary.json for scripts, PNG plots and a one-page report.md for people.

#include <optional>
#include <string>
#include <vector>

#include "scanstop_mission/mission_state.h"

namespace scanstop {
namespace mission {

/// Figures of a finished (or stopped) mission.
/// A mesh against the world's true surfaces (simulation).
struct MeshAccuracy {
  double median_m = 0.0, rms_m = 0.0, p95_m = 0.0;  ///< distance of its surface to the world [m]
  double surface_coverage = 0.0;                    ///< share of the visible surface within 3 cm of it [0..1]
  size_t triangles = 0;
};

struct Summary {
  std::string world;
  std::string state;
  int scans = 0;
  double coverage = 0.0;  ///< observed share of the reachable floor [0..1]
  int collisions = 0;
  bool complete = false;
  std::string complete_reason;
  bool has_ground_truth = false;
  double slam_error_m = 0.0;  ///< final SLAM position error against ground truth [m]
  double slam_error_yaw_deg = 0.0;
  double odom_error_m = 0.0;  ///< final odometry-only position error against ground truth [m]
  double odom_error_yaw_deg = 0.0;
  /// Absolute trajectory error (simulation): the position error of every scan with a true pose,
  /// at SLAM's poses as finally optimized (ScanRecord::map_pose), RMS and max; the same for the
  /// yaw and for odometry alone. ate_scans = 0: no ground truth.
  int ate_scans = 0;
  double ate_rms_m = 0.0;
  double ate_max_m = 0.0;
  int ate_max_scan = -1;  ///< SLAM index of the scan with the largest error
  double ate_yaw_rms_deg = 0.0;
  double ate_yaw_max_deg = 0.0;
  double odom_ate_rms_m = 0.0;
  double odom_ate_max_m = 0.0;
  /// True clearance of the body (simulation): the smallest over every motion, the straight legs
  /// measured and those that came closer than 5 cm. has_clearance false: not measured.
  bool has_clearance = false;
  double min_clearance_m = 0.0;
  int clearance_legs = 0;
  int close_legs = 0;
  double compute_per_cycle_mean_s = 0.0;  ///< register + plan wall time per cycle [s]
  double compute_per_cycle_max_s = 0.0;
  double scan_time_mean_s = 0.0;    ///< modelled scan duration [s]
  double elapsed_s = 0.0;           ///< wall time of the mission [s]
  double modelled_time_s = 0.0;     ///< time the steps would take on the robot [s]
  double modelled_scan_s = 0.0;     ///< ... of it scanning [s]
  double modelled_drive_s = 0.0;    ///< ... driving [s]
  double modelled_compute_s = 0.0;  ///< ... registering and planning [s]
  int unconverged_registrations = 0;
  /// In simulation: the share of the world's truly reachable floor (from the world mesh) that the
  /// map observed. `coverage` is the explorer's own figure, counted on the floor it can reach in its
  /// map: a door it never passed hides what lies behind it there, not here.
  bool has_true_coverage = false;
  double true_coverage = 0.0;      ///< [0..1]
  double true_reachable_m2 = 0.0;  ///< the truly reachable floor [m^2]
  /// In simulation: the share of the world's surface visible from the truly reachable floor
  /// (eval::visibleSurface) that the map holds within 3 cm (eval::mapSurfaceCoverage).
  bool has_surface_coverage = false;
  double surface_coverage = 0.0;  ///< [0..1]
  size_t surface_visible = 0;     ///< visible surface elements (5 cm)
  /// In simulation, with a mesh: its distance to the world's true surfaces (area-weighted samples of
  /// its faces every 1 cm, eval::measureSurfaceAccuracy) and the share of the visible surface it
  /// covers within 3 cm.
  bool has_mesh_accuracy = false;
  MeshAccuracy mesh;
};

/// Ground-truth coverage of a simulated run (eval::groundTruthCoverageOfRun on the final map).
struct TrueCoverage {
  double coverage = 0.0;      ///< observed / reachable [0..1]
  double reachable_m2 = 0.0;  ///< [m^2]
  /// The visible surface held by the map [0..1] and the visible elements; nullopt: not measured.
  std::optional<double> surface_coverage;
  size_t surface_visible = 0;
  std::optional<MeshAccuracy> mesh;  ///< the mesh's accuracy; nullopt: no mesh or not measured
};

/// Computes the summary of a mission state.
Summary summarize(const MissionState& state);

/// The summary as one JSON object.
std::string toJson(const Summary& s);

/// Per-scan poses and errors as CSV (index, SLAM, registered, odometry and true pose, errors).
std::string trajectoryCsv(const MissionState& state);

/// Writes summary.json, coverage.png, trajectory.png, pose_error.png (simulation),
/// trajectory.csv and report.md into run_dir (atomically).
/// `images` lists further images (relative to run_dir, e.g. the explorer's per-step figures) that the
/// report links. Returns the path of report.md. Throws IoError.
/// `truth`: the ground-truth coverage when the run was simulated (summary.json and the report show it).
/// `script_plots`: make_report.py draws the plots afterwards (report.html, report_coverage.png,
/// report_trajectory.png, report_pose_error.png): report.md links those and the PNGs above are not drawn.
std::string writeReport(const MissionState& state, const std::string& run_dir, const std::vector<std::string>& images,
                        const std::optional<TrueCoverage>& truth = std::nullopt, bool script_plots = false);

/// Runs `script` RUN_DIR (make_report.py) with its output in run_dir/make_report.log and waits up to
/// `timeout_s` (then kills it). Returns "" on success, else what went wrong (exit status, signal,
/// timeout, cannot start), for a warning.
std::string runReportScript(const std::string& script, const std::string& run_dir, double timeout_s);

}  // namespace mission
}  // namespace scanstop
