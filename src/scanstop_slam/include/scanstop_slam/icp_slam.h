#pragma once
/// ICP SLAM (thesis 4.2/4.3): every new scan is registered against all earlier scans (the whole
/// map in one persistent voxel index), starting from the last corrected pose composed with the
/// odometry delta since then. A failed registration keeps the odometry-based pose and is flagged.
/// The map is written to a map directory after every scan and can be loaded back.
///
/// Global relaxation (SlamConfig::relax, issue #17 point 3; Lu-Milios / 3DTK slam6D style): after
/// the registration against the map, the new scan is also registered pairwise against a few
/// earlier scans that overlap it (the previous one, the nearest ones, and loop candidates: near in
/// space, far back in index); each accepted pairwise result is an edge of a pose graph over all
/// scans (pose_graph.h). The registration against the map is an edge too (from the previous scan,
/// at the pose the map holds it; when it failed and no pairwise edge joins the previous scan, a weak
/// odometry edge: 5 cm, 1 deg). The graph is then solved. When that moves a pose farther than
/// relax_update_m / relax_update_rad from the pose the map holds it at, every moved pose is
/// applied: poses.csv is rewritten (the replaced poses go to pose_history.csv), and the voxel map
/// is rebuilt from all scans at their corrected poses (read back from the map directory, or from
/// the kept downsampled points when there is none).

#include <limits>
#include <memory>
#include <string>

#include "scanstop_common/cloud.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_slam/icp.h"
#include "scanstop_slam/pose_graph.h"

namespace scanstop {
namespace slam {

/// The ICP settings of the SLAM: IcpConfig's (the thesis' ICP) with point-to-plane steps. On the
/// simulator's noisy 400-plane scans point-to-point is pulled along the travel direction by the
/// scans' different coverage edges (room_10x8 seed 7 replay, with voxel means: ATE RMS 1.6 cm /
/// max 4.0 cm point-to-point, 0.7 / 2.6 cm point-to-plane; docs/decisions.md).
inline IcpConfig slamIcpDefaults() {
  IcpConfig c;
  c.method = IcpMethod::point_to_plane;
  return c;
}

struct SlamConfig {
  IcpConfig icp = slamIcpDefaults();
  /// Coarse-to-fine: first ICP with this correspondence distance (odometry can be off by more than
  /// c_max after a long leg: 20 cm and 3 deg are common), then the thesis' c_max from there.
  /// <= c_max: a single stage.
  double coarse_c_max_m = 0.3;
  /// The coarse stage steps point-to-point (the thesis' ICP) whatever icp.method says: far from the
  /// optimum, with 50 planes, point-to-plane slides along a corridor where the door jambs would
  /// hold point-to-point (corridor rostest, 50 planes: scan 6 slid 84 cm).
  bool coarse_point_to_point = true;
  /// Refinement: after the thesis' stage, ICP again from its result with unique matches
  /// (IcpConfig::unique_matches: no pull back onto the map's edges) to these tighter tolerances.
  /// room_10x8 route (15 scans, sim_route.test): final error 2.6 cm / 0.44 deg -> 0.3 cm / 0.12 deg.
  /// refine_t_c_m = 0: no refinement (the thesis' ICP alone) [m], [0, 0.01]
  double refine_t_c_m = 0.00005;
  double refine_r_c_rad = 0.002 * M_PI / 180;  ///< [rad], (0, 0.01]
  /// [1, 10000]; not settled by then: the thesis stage's result. Unique matches creep where the
  /// thesis stage was pulled far (room_10x8, a scan into the room's unmapped east half: 97
  /// iterations to undo 13 cm), so the bound is generous.
  int refine_max_iterations = 150;
  /// source points of the refinement: one per voxel of this size (its steps are small and many, so
  /// a sparser subset keeps it cheap) [m], [0, 1]
  double refine_source_voxel_m = 0.06;
  /// The refinement corrects a bias of a few centimetres: when it moves the thesis stage's result
  /// farther than this, it has slid (unique matches leave weakly held directions free; room_10x8's
  /// corridor before same-side pairs: 80 cm and 18 deg) and the thesis stage's result stands. It
  /// undoes up to ~15 cm of edge pull-back by the coarse stage [m], [0, 10]; [rad], [0, pi]
  double refine_max_correction_m = 0.25;
  double refine_max_correction_rad = 2.0 * M_PI / 180;
  double source_voxel_m = 0.02;  ///< scan points used for matching: one per voxel of this size (0 = all) [m]
  /// true: that one point is the voxel's mean (voxelCentroids), for every matching subset (source,
  /// coarse, refine, relaxation); false: the voxel's first point in scan order (voxelDownsample),
  /// which sits where the sweep entered the voxel: room_10x8 seed 7 replay (point-to-plane) ATE
  /// RMS 2.4 / max 6.2 cm with first points, 0.7 / 2.6 cm with means.
  bool source_centroids = true;
  int max_points_per_voxel = 30;  ///< map points kept per c_max voxel (bounds memory and query time)
  double map_spacing_m = 0.0;     ///< a map point joins only if none of its voxel is closer [m] (0 = first come)
  /// Odometry scale: the initial guess scales the odometry's translation since the last scan by
  /// the factor that maps the odometry's earlier legs onto the registered ones (least squares over
  /// every converged, not degenerate registration (odom_scale_both_ends: at both ends of the leg) after at least
  /// odom_scale_min_travel_m of odometry travel; 1 until two such legs exist; clamped to [0.8, 1.25]). Where a
  /// registration is degenerate (a corridor along its axis) the guess is what stands along the weak direction, so an
  /// odometry that reads 3 % long (the thesis profile) otherwise drifts 3 cm per metre there.
  bool odom_scale_estimation = true;
  double odom_scale_min_travel_m = 0.3;  ///< [m], [0.01, 100]
  /// A leg tells the odometry scale and turn (odom_turn_estimation) only when the registrations at
  /// both of its ends are evidence (converged, not degenerate), not only the later one: a leg that
  /// starts at a degenerate scan (held at its guess along a corridor's axis, off by the scale's own
  /// error) carries that scan's error into the estimate, which then drives the next degenerate
  /// scans the same way (corridor seed 2: scale 1.036-1.039 for the true 1.030, 1-4 cm along the
  /// axis per degenerate scan; replay ATE RMS / max 7.8 / 12.5 -> 6.6 / 10.6 cm). false: the
  /// later end alone (the rule before 2026-12-08).
  bool odom_scale_both_ends = true;
  /// Odometry turn calibration: the guess's yaw since the last scan is k * yaw + b (b once per leg
  /// of at least odom_scale_min_travel_m: the turn a forward motion ends with, its curvature) and
  /// its translation turns by (k - 1) * yaw (the robot turned that much more or less before it
  /// drove), k and b by least squares over the same legs as the scale (1 and 0 until three legs
  /// exist with at least odom_turn_min_total_rad of turning between them; k clamped to [0.9, 1.1],
  /// b to +-3 deg). The thesis profile turns 2 % too far and ends each forward motion 0.5 deg
  /// turned with 1 deg/m of curvature: a 90 deg turn and a 1.4 m leg put the guess 4-5 cm off
  /// sideways, along a hall's or corridor's weak direction when the leg crosses it (office_large
  /// seed 1: guess off per leg at the 90th percentile 6.0 -> 3.8 cm, in yaw RMS 1.9 -> 0.9 deg).
  bool odom_turn_estimation = true;
  double odom_turn_min_total_rad = 1.0;  ///< [rad], [0, 1000]
  /// Odometry prior (issue #17 point 2): along weak directions the registration against the map
  /// weighs the odometry guess by the error model below instead of keeping it exactly
  /// (IcpConfig::degeneracy_remap, which then applies only to the relaxation's pairwise
  /// registrations). A weak direction is rarely empty: a corridor's door jambs and side rooms hold
  /// its axis a little, and the remap threw that away, leaving the odometry's 1 % per leg to add up.
  bool odometry_prior = false;
  /// The guess's standard deviation in position: prior_sigma_m (floor) and prior_sigma_per_m per
  /// metre of odometry travel since the last scan, added in quadrature, the same along and across
  /// the leg (the thesis profile: 1 % distance noise per leg, the scale estimate's own error,
  /// curvature; wheel slip on a real floor) [m], (0, 10]; [1], [0, 1]
  double prior_sigma_m = 0.01;
  double prior_sigma_per_m = 0.02;
  /// ... in yaw (and, 6dof, roll and pitch: prior_sigma_rad alone; z: prior_sigma_m): a floor, per
  /// radian of odometry turn and per metre of travel (the thesis profile: 2 +- 1 % of a turn,
  /// 0.5 deg at the end of each forward motion, curvature 1 deg/m), in quadrature [rad], (0, pi];
  /// [rad/rad], [0, 1]; [rad/m], [0, 1]
  double prior_sigma_rad = 1.0 * M_PI / 180.0;
  double prior_sigma_rad_per_rad = 0.03;
  double prior_sigma_rad_per_m = 0.01;
  /// A registration weighed against the prior (one with weak directions) that ends farther than
  /// this from it, in standard deviations of the error model (Mahalanobis distance over x, y, yaw),
  /// has been pulled by pairs
  /// that do not belong together, not corrected (furnished_1 seed 2 scan 2: point-to-plane pairs
  /// at the map's edge pulled the scan 55 cm back onto the map, 24 sigma): it is registered again
  /// the old way, keeping the guess along weak directions (IcpConfig::degeneracy_remap), and
  /// that result stands (logged). [sigma], (0, 1e6]
  double prior_gate = 5.0;
  /// Odometry gate (issue #17): a converged registration that ends farther than this from its guess,
  /// in standard deviations of the error model above (prior_sigma_*; Mahalanobis distance over x, y,
  /// yaw), is registered again from the guess without the coarse stage; the second result stands
  /// when it lies within the gate and fits the map as well (rms no more than odometry_gate_rms_ratio
  /// times the first's), else the first stands (odometry that is truly off, e.g. after a slip,
  /// keeps its correction). The coarse stage's wide pairs can slide a scan with little overlap along
  /// a weakly held direction: the house seed 2, scan 5 (2.7 m leg, guess 12 cm off) 45 cm, 4 cm
  /// without it. [sigma], [0, 1e6]; 0: off (default on since 2026-12-05, docs/decisions.md)
  double odometry_gate = 5.0;
  double odometry_gate_rms_ratio = 1.1;  ///< [1], [1, 100]
  /// When neither result lies within the gate, a third registration keeps the guess along the
  /// directions weak at failure_retry_degeneracy_ratio; it stands within the gate at an rms of at
  /// most odometry_gate_rms_ratio times the first's, or this ratio when the first result's own
  /// condition counts as weak at that ratio (a slide fits a little better than the truth, a guess
  /// that is truly off fits much worse: office_large seed 1 scan 88 1.13, office_loop seed 1 scan
  /// 61 1.48) [1], [1, 100]
  double odometry_gate_weak_rms_ratio = 1.25;
  /// A registration that fails (no convergence within max_iterations, or a correction beyond
  /// max_correction) is registered again with IcpConfig::degeneracy_ratio raised to this (more
  /// directions count as weak and keep the odometry guess); the second result stands when it
  /// converges (within odometry_gate when that is on), else the odometry pose is kept as before.
  /// furnished_1 seed 2 scan 2: crept 2.5 m along a weakly held direction (condition 28), kept
  /// 6.6 cm off, every later scan 5-7 cm off; registered again 1.9 cm. [1], [0, 1]; 0 (or not above
  /// degeneracy_ratio): off
  double failure_retry_degeneracy_ratio = 0.05;
  /// Request checks (registerScan refuses, changing nothing): a finite scan point farther than this
  /// from base_link is not a measurement [m], [0.1, 10000]
  double max_point_distance_m = 100.0;
  /// Odometry moving farther than this between two scans is not a motion of the robot (a reset or
  /// a corrupt pose) [m], [0.01, 100000]
  double max_odom_jump_m = 20.0;

  // Global relaxation (see the top of this file).
  bool relax = false;  ///< pose graph relaxation after every scan
  /// Pairwise edges per new scan to its nearest earlier scans (pose distance; the previous scan is
  /// always one of them), [0, 100]. 0: none; the chain is then the registration against the map
  /// alone (an edge from the previous scan, always added when that registration converged), and
  /// pairwise edges join loop candidates only.
  /// office_loop replay (planes 100, 128 scans): 0 -> error RMS 9.2 cm, max 22.3 cm (16.9 / 102.8 cm
  /// without relaxation); 3 was measured only before the map registration became an edge (20.6 / 60.3 cm).
  int relax_neighbours = 0;
  /// ... and to up to this many loop candidates: the nearest earlier scans at least
  /// relax_loop_min_gap indices back [0, 100]
  int relax_loop_candidates = 2;
  /// A scan this many indices back or more is a loop candidate, and an edge to it is a loop edge
  /// (robust loss, PoseGraphConfig) [2, 100000]
  int relax_loop_min_gap = 8;
  /// Candidates lie within this distance of the new scan's pose [m], (0, 1000]
  double relax_max_distance_m = 6.0;
  /// Kept per scan for pairwise registration: its points downsampled to one per voxel of this size
  /// (also the map's points when it is rebuilt without a map directory) [m], [0.01, 1]
  double relax_voxel_m = 0.05;
  /// A pairwise result is an edge only when converged with at least this overlap (correspondences /
  /// source points) [0, 1] ...
  double relax_min_overlap = 0.3;
  /// ... and at most this RMS of its correspondences [m], (0, 1]
  double relax_max_rms_m = 0.04;
  /// Apply the relaxation (rewrite poses, rebuild the map) when a pose moves farther than this from
  /// where the map holds it [m], [0, 10]; [rad], [0, pi]
  double relax_update_m = 0.01;
  double relax_update_rad = 0.2 * M_PI / 180;
  PoseGraphConfig graph;  ///< the solver and the robust loss of loop edges
  void validate() const;
};

/// Why a scan (base_link frame, NaN = no return) cannot be registered, or "" when it can: no
/// point, no finite point, an infinite coordinate (NaN marks invalid points, Inf is corrupt), or a
/// point farther than max_point_distance_m from base_link. Names the first bad point's index.
std::string scanProblem(const PointCloud& scan_base, double max_point_distance_m);

/// The information matrix (inverse covariance of x, y, yaw of T_target_source, in the target's
/// frame; see pose_graph.h) of a pairwise registration result, for its pose graph edge. Stand-in
/// until IcpResult carries its own Hessian: the point-to-plane Gauss-Newton J^T J over the final
/// correspondences (source points within c_max of the target at T, on a planar target voxel; with
/// ignore_horizontal not on floors or ceilings), J = n^T d(T p)/d(x, y, yaw), averaged, times
/// kEffectivePoints = 50 independent points, over sigma^2 = max(rms, 5 mm)^2 of those point-to-plane
/// distances, plus 1 on the diagonal (a 1 m / 1 rad prior: positive definite also on a corridor, where
/// the walls leave x free and J^T J says so).
Eigen::Matrix3d pairwiseInformation(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source,
                                    const Eigen::Isometry3d& T_target_source, const IcpConfig& config);

/// A problem of the map directory found at start: a scan file that could not be loaded (skipped,
/// the map goes on without it) or a bad poses.csv line.
struct SkippedScan {
  std::string file;    ///< path of the bad file
  std::string reason;  ///< what was wrong (the loader's error)
};

/// One registered scan.
struct Registration {
  uint32_t index = 0;
  Pose2D map_pose;  ///< corrected pose of base_link in the map frame
  Pose2D guess;     ///< the initial guess from odometry
  bool converged = false;
  std::string failure;  ///< why the registration failed (empty when it converged)
  int iterations = 0;
  size_t correspondences = 0;
  double rms_m = 0.0;
  double overlap = 0.0;
  double time_s = 0.0;  ///< compute time [s]
  /// The refinement stage: how far it moved the thesis stage's result, and whether that was too far
  /// (SlamConfig::refine_max_correction_m: the thesis stage's result stands).
  double refine_moved_m = 0.0;
  double refine_moved_rad = 0.0;
  bool refine_rejected = false;
  /// Global relaxation (SlamConfig::relax): pairwise edges tried / accepted for this scan (the
  /// edge of the registration against the map, or the odometry edge, is not counted), whether the
  /// graph was solved, and whether the result was applied (poses rewritten, map rebuilt).
  int relax_edges_tried = 0;
  int relax_edges = 0;
  bool relax_solved = false;
  bool relaxed = false;
  /// Applied: earlier scans whose pose changed, and the largest change [m], [rad]. map_pose is
  /// the new scan's pose after the relaxation in any case.
  size_t relax_moved = 0;
  double relax_max_moved_m = 0.0;
  double relax_max_moved_rad = 0.0;
  double relax_time_s = 0.0;  ///< pairwise registrations + solve + applying [s] (part of time_s)
  std::string relax_problem;  ///< the relaxation's trouble (solver failure, poses.csv not rewritten), or ""
  /// The information matrix of the final stage (the refinement's when it stands, else the thesis
  /// stage's; IcpResult): condition [1] (NaN: no planar pair, also for the first scan), degenerate
  /// (smallest / largest eigenvalue < IcpConfig::degeneracy_ratio), the weak direction (x, y, yaw
  /// for 3dof; x, y, z, rx, ry, rz for 6dof; empty without information) and whether remapping
  /// kept the guess along it.
  double condition = std::numeric_limits<double>::quiet_NaN();
  double odom_scale = 1.0;         ///< the odometry scale the guess used (SlamConfig::odom_scale_estimation)
  double odom_turn_scale = 1.0;    ///< the turn scale k the guess used (SlamConfig::odom_turn_estimation)
  double odom_leg_turn_rad = 0.0;  ///< the turn b per leg the guess used [rad]
  /// The odometry's motion since the last scan (scaled as the guess), for the prior's error model.
  Pose2D odom_leg;
  /// SlamConfig::odometry_prior on a degenerate registration: how far its final stage's result
  /// lies from where solution remapping would have kept it (IcpResult::weak_gain_m) [m], [rad].
  double weak_gain_m = 0.0;
  double weak_gain_rad = 0.0;
  /// How far the result weighed against the prior lies from it, in the prior's standard deviations
  /// (Mahalanobis distance over the ICP's pose parameters), and whether that was beyond
  /// SlamConfig::prior_gate (the result without the prior's weight stands then). 0 / false
  /// without odometry_prior.
  double prior_distance = 0.0;
  bool prior_rejected = false;
  /// SlamConfig::odometry_gate: the first result's distance from the guess [sigma] (0 when off),
  /// whether it was beyond the gate (registered again without the coarse stage) and whether that
  /// second result stands; when it does not, a third registration counts more directions weak
  /// (failure_retry_degeneracy_ratio) and gate_widened says that one stands.
  double guess_distance = 0.0;
  bool gate_retried = false;
  bool gate_replaced = false;
  bool gate_widened = false;
  /// SlamConfig::failure_retry_degeneracy_ratio: whether the first registration failed and was
  /// registered again, its failure, and whether the second result stands.
  bool failure_retried = false;
  bool failure_replaced = false;
  std::string first_failure;
  bool degenerate = false;
  Eigen::VectorXd weak_direction;
  bool remapped = false;
};

/// A scan's current pose in the map.
struct ScanPose {
  uint32_t index = 0;
  double stamp_s = 0.0;
  Pose2D map_pose;
};

class IcpSlam {
 public:
  /// map_dir may be empty (nothing persisted); otherwise its scans are loaded (resume). A scan file
  /// that cannot be read (missing, truncated, corrupt) is skipped and listed in skippedScans(); its
  /// poses.csv entry stays, so indices and the trajectory are kept. A corrupt poses.csv: IoError
  /// naming it from scanstop_common's MapDirectory, or (once it skips bad lines) its report.
  IcpSlam(const SlamConfig& config, const std::string& map_dir = "");

  /// Registers a scan given in base_link (NaN points ignored) taken at odom_pose; sensor_origin
  /// (scanner centre in base_link) and stamp are stored with it. Throws std::invalid_argument,
  /// changing nothing, for a bad request: scanProblem(), a non-finite pose, sensor origin or stamp,
  /// or an odometry jump beyond max_odom_jump_m since the last scan. Throws IoError (nothing changed
  /// in memory) when the map directory cannot be written.
  Registration registerScan(const PointCloud& scan_base, const Pose2D& odom_pose,
                            const Eigen::Vector3d& sensor_origin = Eigen::Vector3d::Zero(), double stamp_s = 0.0);

  /// The current map poses of all scans in the map (not the skipped ones), in index order; after a
  /// relaxation the corrected ones.
  std::vector<ScanPose> poses() const;
  /// The pose graph of the relaxation: one node per scan of poses(), in that order (edges only with relax).
  const PoseGraph& graph() const { return graph_; }

  /// Registers a scan (base_link) against another map (e.g. earlier scans at their true poses, for
  /// measuring one registration alone) from guess, with this SLAM's stages and checks exactly as
  /// registerScan registers against its own map; changes nothing. index and odom_scale stay unset.
  /// odom_leg: the odometry's motion from the scan the guess starts at to this one (the prior's
  /// error model, SlamConfig::odometry_prior).
  Registration registerAgainst(const VoxelMap& target, const PointCloud& scan_base, const Pose2D& guess,
                               const Eigen::Vector3d& sensor_origin, const Pose2D& odom_leg) const;
  /// The inverse covariance of a guess after an odometry leg (SlamConfig::prior_sigma_*), in the
  /// pose parameters of the ICP (3x3 x, y, yaw for 3dof; 6x6 for 6dof).
  Eigen::MatrixXd priorInformation(const Pose2D& odom_leg) const;

  /// Scans in the map including skipped ones: the index the next scan gets.
  size_t scanCount() const { return count_; }
  const VoxelMap& map() const { return map_; }
  const SlamConfig& config() const { return config_; }
  const Pose2D& lastMapPose() const { return last_map_; }
  const Pose2D& lastOdomPose() const { return last_odom_; }
  /// T_map_odom: maps odometry poses into the map frame.
  Pose2D mapFromOdom() const { return last_map_ * last_odom_.inverse(); }
  /// The map directory (null when not persisting).
  const MapDirectory* mapDirectory() const { return dir_.get(); }
  /// Scans of the map directory that could not be loaded at start.
  const std::vector<SkippedScan>& skippedScans() const { return skipped_; }
  /// Why a scan at odom_pose would be refused for its odometry (non-finite, or a jump beyond
  /// max_odom_jump_m since the last scan), or "".
  std::string odomProblem(const Pose2D& odom_pose) const;

 private:
  /// One point per voxel_m voxel (SlamConfig::source_centroids: the mean, else the first).
  std::vector<Eigen::Vector3f> sample(const std::vector<Eigen::Vector3f>& points, double voxel_m) const;
  std::vector<Eigen::Vector3f> coarseSource(const std::vector<Eigen::Vector3f>& source) const;
  std::vector<Eigen::Vector3f> refineSource(const std::vector<Eigen::Vector3f>& source) const;
  /// The stages of every registration, from start: coarse (coarse_c_max), the thesis stage, the
  /// refinement (its figures into r when given); the correction bound applies to the whole move.
  /// prior_information (priorInformation()): the start is a prior weighed by it; null: kept
  /// along weak directions (IcpConfig::degeneracy_remap). icp_config: the stages' ICP settings
  /// (null: config().icp).
  IcpResult registerStages(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source,
                           const Eigen::Isometry3d& start, const Eigen::Vector3f& origin, Registration* r,
                           const Eigen::MatrixXd* prior_information = nullptr, bool coarse = true,
                           const IcpConfig* icp_config = nullptr) const;
  /// Mahalanobis distance of result from guess over x, y, yaw under prior_information [sigma].
  double guessDistance(const Pose2D& guess, const Pose2D& result, const Eigen::MatrixXd& prior_information) const;
  /// registerStages on the scan's source subset from r.guess; fills r's registration figures and map_pose.
  void registerInto(const VoxelMap& target, const PointCloud& scan_base, const Eigen::Vector3f& origin,
                    Registration& r) const;
  /// Pairwise edges from the new scan (kept points, pose guess) to earlier scans, into graph.
  void addRelaxEdges(PoseGraph& graph, const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin,
                     Registration& r) const;
  /// Rebuilds map_ from all scans at their current poses.
  void rebuildMap();
  /// What the relaxation keeps per scan.
  struct KeptScan {
    uint32_t index = 0;
    double stamp_s = 0.0;
    Pose2D pose;                                       ///< where the map holds it (applied)
    std::vector<Eigen::Vector3f> points;               ///< relax_voxel_m-downsampled, base_link (relax only)
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();  ///< sensor origin in base_link
    Pose2D odom;                                       ///< its odometry pose
    /// converged and not degenerate: the legs it ends (and, with odom_scale_both_ends, starts) tell
    /// the odometry scale and turn
    bool scale_evidence = true;
  };
  /// Whether the leg from kept scan i - 1 to i (i >= 1) tells the odometry scale and turn
  /// (SlamConfig::odom_scale_both_ends).
  bool scaleEvidence(size_t i) const;
  /// SlamConfig::odom_scale_estimation's factor from the kept scans' legs (1 without evidence).
  double odomScale() const;
  /// SlamConfig::odom_turn_estimation's k and b from the kept scans' legs ({1, 0} without evidence).
  std::pair<double, double> odomTurn() const;
  std::vector<KeptScan> kept_;
  PoseGraph graph_;
  SlamConfig config_;
  VoxelMap map_;
  std::unique_ptr<MapDirectory> dir_;
  size_t count_ = 0;
  Pose2D last_map_, last_odom_;
  std::vector<SkippedScan> skipped_;
};

}  // namespace slam
}  // namespace scanstop
