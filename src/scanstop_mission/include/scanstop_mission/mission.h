#pragma once
/// The scan-stop cycle (thesis chapters 1, 5.5, 8): scan -> register -> plan -> drive the path
/// (rotate, then straight segments of at most d_max; scan and register at intermediate landmarks)
/// -> repeat until the explorer reports exploration complete (then, with return_home, drive back to
/// the start), the scan budget is reached or the user aborts. ROS-free: the steps go through a RobotSystem; the state
/// is saved after every step.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "scanstop_mission/dead_reckoning.h"
#include "scanstop_mission/mission_state.h"
#include "scanstop_mission/robot_system.h"

namespace scanstop {
namespace mission {

/// Mission parameters (the node maps its ROS parameters onto these fields in one place).
struct MissionConfig {
  int planes = 400;   ///< planes per 3D scan: 50, 100, 200 or 400
  int max_scans = 0;  ///< scan budget; 0 = until exploration is complete
  /// Longest straight motion [m] (thesis d_max) until a plan says the explorer's (PlanResult::d_max_m):
  /// one source, the explorer's d_max_m (config/explorer.yaml); this is the fallback.
  double d_max_m = 2.0;
  double waypoint_tolerance_m = 0.05;    ///< a waypoint closer than this is reached [m]
  double heading_tolerance_rad = 0.005;  ///< rotations smaller than this are skipped [rad]
  /// Scans at intermediate landmarks (thesis 5.5) only once the path driven since the last scan is
  /// at least this long [m]; 0 = at every landmark the explorer marks (the thesis). The target is
  /// always scanned.
  double min_scan_travel_m = 0.0;
  /// Which intermediate landmarks of a path get a scan: "landmarks" (the thesis: every landmark
  /// the explorer marks, once min_scan_travel_m / home_scan_travel_m have been driven) or "error"
  /// (only where going on without one would let the pose grow too uncertain: the robot scans at a
  /// landmark when what odometry cannot see (DeadReckoning, the leg_check_* error model) would,
  /// after the next leg's turn and length, exceed scan_error_bound_m of position; issue #19 point
  /// 4). The target is always scanned.
  std::string scan_on_the_way = "landmarks";
  /// "error" mode: the position bound past which the robot scans first [m], (0, 10]
  double scan_error_bound_m = 0.15;
  /// Once exploration is complete, drive back to the first scan's position (scanning on the way as
  /// on any path, and at the end) before the mission ends: the robot comes back, and its last
  /// scan registers against the well-mapped start instead of the far end of a corridor.
  bool return_home = true;
  double home_tolerance_m = 0.5;  ///< within this of the first scan's position the robot is back [m]
  /// On the way back, scans at intermediate landmarks only once the path driven since the last scan
  /// is at least this long [m] (min_scan_travel_m when smaller): the way leads over mapped ground,
  /// the scans there only hold the pose (room_10x8, min_scan_travel 2.0, seeds 1-3: 3 m -> 4 scans
  /// on the way back, 4 m -> 3, no collision on the way back either way).
  double home_scan_travel_m = 4.0;
  /// After a collision or stall the robot backs off straight backwards by this much (the way it
  /// came on a forward leg), so that the next motion does not start in contact [m], [0, 1]; 0 = off.
  double contact_backoff_m = 0.3;
  /// Where the contact is taken to be: the latest scan's point in the body's height band nearest to
  /// the robot within this distance + 0.1 m of base_link (not behind it); without one, this far ahead in the
  /// driving direction (the body's front edge from its centre; the Pioneer 2 DX's 0.26 m swept
  /// radius plus a little) [m], [0, 2]. The point joins MissionState::contacts and every later plan
  /// as an obstacle.
  double contact_offset_m = 0.3;
  /// Radius of the obstacle disc of a contact located at a scanned point (the point is known to
  /// within the odometry since the scan: a few cm; the explorer inflates it by the robot's radius).
  /// A contact placed contact_offset ahead is a guess and gets the explorer's contact_radius_m
  /// (0.15 m). A large disc at a door jamb closes the door [m], (0, 2]
  double contact_point_radius_m = 0.05;
  /// A safety bound: after this many contacts the mission stops exploring (the map, the mesh and
  /// the report are kept) and ends Failed with the reason, instead of trying again, [1, 1000].
  int max_contacts = 5;
  /// The safety check before every straight leg: the body (a disc of leg_check_radius_m) swept along
  /// the leg against the latest scan's points in the body's height band (carried to the robot's
  /// present pose by odometry; relative to the robot, so SLAM's error does not enter). The leg ends
  /// leg_check_margin_m before the first place where at least leg_check_min_points points lie in
  /// the body; a leg shortened so is logged, the target marked unreachable, the robot rescans and
  /// the mission replans. false: no check (the thesis).
  bool leg_check = true;
  double leg_check_radius_m =
      0.28;  ///< the body's swept radius plus a margin [m], (0, 2] (mission_node: robot_body/radius + 0.02)
  double leg_check_margin_m = 0.05;  ///< stop this far before the first obstruction [m], [0, 1]
  /// A leg the check stops at an obstruction before its waypoint is followed by a scan where the
  /// robot stops (re-localization, or the target given up): the robot then stops this far before
  /// the obstruction (at least leg_check_margin_m), so that the scan sees past it. A scan taken
  /// with the body 5 cm before furniture sees about half of its points and may fail registration
  /// (turtlebot3_house seed 1, scan 41: 25 cm of drift after it). [m], [0, 2]
  double obstruction_standoff_m = 0.3;
  double leg_check_min_z_m = 0.03;  ///< the body's height band: from (above the floor layer) [m]
  double leg_check_max_z_m = 0.6;   ///< ... to (the body's and the mast's height) [m] (mission_node: robot_body/height)
  double leg_check_self_m = 0.3;    ///< scan points this close to base_link are the robot itself [m], [0, 2]
  int leg_check_min_points = 3;     ///< points that make an obstruction (random readings are single), [1, 1000]
  /// What odometry cannot see since the scan (DeadReckoning): the swept disc grows by the position
  /// bound and, at x ahead, by x * tan(heading bound). The heading bound is leg_check_turn_error
  /// times the |turns| summed since the scan plus leg_check_drift per metre driven; the position
  /// bound grows on every metre driven by tan(heading bound) plus leg_check_distance_error.
  /// furnished_2: a 190 deg turn beside a table edge, 2 cm off it (at the estimated heading the edge
  /// lay beside the leg, at the true one ahead); five legs (288 deg, 4.3 m) after a scan, 0.31 m
  /// beside the estimate, into a door jamb. All 0 = the plain disc.
  double leg_check_turn_error = 0.03;               ///< heading error per radian turned [rad/rad], [0, 0.5]
  double leg_check_drift = 0.015;                   ///< heading drift per metre driven [rad/m], [0, 0.5]
  double leg_check_distance_error = 0.04;           ///< position error per metre driven [m/m], [0, 0.5]
  double leg_check_turn_position_m_per_rad = 0.03;  ///< position error per radian turned [m/rad], [0, 0.5]
  /// A leg whose direction lies more than 90 deg from the robot's heading is driven backwards after
  /// the smaller turn (the scan sees all around and nothing is sensed while driving, so backwards is
  /// as safe; a rotation's error grows with its angle: a 170 deg turn is +-5 deg and +-5 cm, its
  /// complement +-0.3 deg and +-0.5 cm). false: every leg forwards after turning to face it.
  bool reverse_legs = true;
  /// A leg the check stops only because of what odometry cannot see (with the plain disc it would
  /// be clear), after at least this much driving since the scan: the robot scans there to
  /// re-localize and goes on with the same path (the target is not marked unreachable). [m], [0, 100]
  double relocalize_min_travel_m = 0.5;
  /// ... or, for a leg whose map clearance (PlanNext.clearance) the bounds do not hold, after at
  /// least this much turning since the scan (a scan after the turn measures the heading the turn
  /// got wrong: furnished_3 seed 4 drove back out of a 0.6 m niche after a 175 deg turn and passed
  /// 0.0 cm from a shelf). [rad], [0, 2 pi]; 2 pi: off
  double relocalize_min_turn_rad = M_PI / 2;
  /// A re-localization scan on the last leg of an exploration path, at most this far from the
  /// target, stands for the target's scan: the mission replans from there instead of driving on and
  /// scanning again (room_10x8: 4 of 19 scans were such pairs, 0.8-1.4 m apart; what the target
  /// would have seen the explorer asks for again if it still lacks). [m], [0, 10]; 0: off
  double relocalize_as_target_m = 1.5;
  /// Planes of a scan taken only to re-localize (the leg check's, and after a target is given up):
  /// registration needs far fewer than the map (a 100-plane scan takes 10 s, not 40 s). 0: planes;
  /// else 50, 100, 200 or 400 (at most planes).
  int relocalize_planes = 100;
  /// A leg the check refuses before the robot moves (an obstruction within leg_check_margin_m of
  /// the body ahead, e.g. a door jamb the leg grazes from where the robot stopped): the robot first
  /// looks for a sidestep of at most this much (0.05 m steps, 16 directions) after which the whole
  /// leg to the same waypoint is clear by the same check, and drives it (backwards when it lies
  /// behind) instead of giving the target up. The house, seed 2: the robot stood 9 cm off in
  /// front of a door and gave up 40 targets behind it one by one. At most one sidestep per
  /// waypoint. [m], [0, 1]; 0 = off.
  double leg_sidestep_m = 0.25;
  /// A straight leg whose true clearance (simulation) falls below this counts as a close leg [m].
  static constexpr double kCloseLeg = 0.05;
  int max_step_retries = 2;  ///< retries of a failed scan, registration, plan or mesh
  /// Wait before retry n (n = 1, 2, ...) of a failed step: n times this [s]. A node that died
  /// mid-call is usually back (respawn) within a few seconds.
  double retry_backoff_s = 1.0;
  int max_consecutive_failed_cycles = 5;  ///< cycles in a row that make no progress before giving up
  int max_cycles = 1000;                  ///< hard bound on plan-drive cycles
  bool build_mesh = true;                 ///< ask the mesher for a mesh at the end (if one runs)
  /// Where the mesher is asked to write the mesh (a path on the mesher's host, .ply or .stl);
  /// empty = the mesher's own default_output (a mesher on another host).
  std::string mesh_output;
  std::string run_dir;  ///< where the state, the log and the report go
  std::string world;    ///< world name for the report (simulation)

  /// Throws ConfigError naming the first bad field.
  void validate() const;
};

/// Runs one mission. run() blocks; pause(), resume() and abort() may be called from other threads.
class Mission {
 public:
  using Log = std::function<void(const std::string&)>;

  /// `info` and `warn` receive progress lines (the node forwards them to rosout).
  Mission(MissionConfig config, RobotSystem& robot, Log info, Log warn);

  /// Loads <run_dir>/mission_state.yaml if it exists and reconciles it with the SLAM map
  /// (scans registered after the last save are adopted). Returns true when a mission was resumed.
  /// Throws IoError when the saved state is corrupt.
  bool loadSavedState();

  /// Runs the cycle to its end; returns the final state (Done, Aborted or Failed).
  State run();

  /// Control requests; each answers false (and changes nothing) when it does not apply, with the
  /// reason in `why`: pause while already paused or finished, resume while not paused, abort after
  /// the end.
  bool pause(std::string* why = nullptr);
  bool resume(std::string* why = nullptr);
  bool abort(std::string* why = nullptr);
  /// Ends the mission for a reason outside it (the ROS master gone longer than master_timeout_s):
  /// like abort, but run() ends Failed with `reason` (saved, so a restarted node resumes from there).
  void end(const std::string& reason);
  /// Records an event in the mission's log and state (a warning also becomes last_error).
  void note(const std::string& what, bool warning = false) { event(what, warning); }
  bool paused() const;

  /// Called (outside the lock) after every state change, e.g. to publish the status at once.
  void setStateListener(std::function<void()> listener) { state_listener_ = std::move(listener); }

  /// A copy of the current state (thread-safe).
  MissionState snapshot() const;
  /// The mesh the mesher wrote at the end of this run (its path on the mesher's host); empty: none.
  const std::string& builtMesh() const { return built_mesh_; }
  std::string statePath() const { return config_.run_dir + "/mission_state.yaml"; }
  std::string logPath() const { return config_.run_dir + "/mission.log"; }

 private:
  enum class Control { Run, Pause, Abort };

  /// run()'s steps. What a step says the cycle does next.
  struct Next {
    enum Kind { Drive, Replan, EndCycles, Finish };
    Kind kind = Drive;
    State state = State::Done;  ///< Finish: the mission ends so, with why
    std::string why;
    static Next drive() { return {}; }
    static Next replan() { return {Replan, State::Done, ""}; }
    static Next endCycles() { return {EndCycles, State::Done, ""}; }
    static Next finishWith(State s, std::string why) { return {Finish, s, std::move(why)}; }
    static Next aborted() { return finishWith(State::Aborted, "aborted by the user"); }
  };
  /// What the cycle carries from one iteration to the next.
  struct Cycle {
    int failed = 0;           ///< cycles in a row without progress
    int home_plans = 0;       ///< plans of the way back to the start (bounded: it may have become unreachable)
    std::string safety_stop;  ///< set when max_contacts is reached: the mission ends Failed with it
  };
  /// Plans the next target (or the way back to the start once exploration is complete and
  /// return_home is on) into `plan`: Drive it, Replan (nothing to drive), EndCycles (done, back home,
  /// budget spent) or Finish.
  Next planStep(const MissionState& now, Cycle& cycle, PlanResult& plan);
  /// Drives plan's waypoints from `first`, scanning where the plan says (landmarks, the target) or
  /// where the leg check needs a re-localization; a waypoint that cannot be reached gives the target
  /// up. Drive (the cycle goes on) or Finish.
  Next drivePath(const PlanResult& plan, size_t first, const MissionState& now, Cycle& cycle);
  /// A target the robot could not reach (a collision or a refused leg): marked unreachable, the
  /// contact bound checked (cycle.safety_stop), a re-localization scan where the robot moved.
  /// True when the mission was aborted meanwhile.
  bool giveUpTarget(const PlanResult& plan, bool collision, Cycle& cycle);
  /// After the cycle: the mesh, and the final state.
  State endMission(const Cycle& cycle);
  /// Ends the mission in state s (an abort after end() becomes Failed with end()'s reason).
  State finish(State s, std::string why);
  /// The path being driven, saved with the state (a restarted mission drives on along it): plan's
  /// waypoints from `next` (none when next is past the end); scan_mark: the scan count before a
  /// scan at waypoint `next` (-1: none).
  void setPath(const PlanResult& plan, size_t next, int scan_mark);
  Eigen::Vector2d home(const MissionState& s) const;  ///< the first scan's position (map frame)
  bool atHome(const MissionState& s) const;           ///< the estimate within home_tolerance_m of it
  bool homeward(const MissionState& s) const;         ///< exploration complete and return_home on

  /// Scans with `planes` (0 or more than MissionConfig::planes: MissionConfig::planes) and registers.
  bool scanAndRegister(int planes = 0);
  /// Adopts the scans SLAM holds beyond the last one the mission knows, up to index `upto`
  /// (exclusive; -1 = all): registered by a mission that died before it could save them, or
  /// still being registered when this mission restarted. Caller holds no lock.
  void adoptScansRegisteredElsewhere(int upto = -1);
  /// Takes SLAM's current pose of every known scan (registeredScanPoses(): after a pose-graph
  /// relaxation they are the corrected ones) into the records, keeping the pose each registration
  /// answered in ScanRecord::registered_pose. Caller holds no lock.
  void adoptCurrentPoses();
  /// How a drive to a waypoint ended.
  enum class Drive {
    Reached,
    Failed,      ///< a motion failed, or the leg check found an obstruction (the target is unreachable)
    Collision,   ///< the robot touched something (booked as a contact, backed off)
    Relocalize,  ///< stopped short: only what odometry cannot see made the leg unsafe; scan, go on
  };
  /// `clearance_m`: the map's clearance of the leg (PlanResult::clearance_m), when known.
  Drive driveTo(const Eigen::Vector2d& waypoint, std::optional<double> clearance_m);
  /// One motion of driveTo: booked (noteMotion); nullopt when it went through, else how the drive
  /// ends (a failure logged; a collision booked as a contact and backed off from).
  std::optional<Drive> rotateBy(double angle_rad);
  std::optional<Drive> driveStraight(double distance_m);  ///< negative: backwards
  std::string deadReckoningText() const;  ///< "x m and a deg since the scan: position +-p m, heading +-h deg"
  /// After a collision on a motion in direction `sign` (+1 forward, -1 backward, 0 a rotation):
  /// records the contact point (none for a rotation) and backs off by contact_backoff_m.
  void escapeContact(int sign, const std::string& what);
  /// The latest scan's obstacle point (body height band) nearest to the robot now, in its present
  /// base_link, within contact_offset_m + 0.1 m and not behind (sign: +1 forward, -1 backward); none: nullopt.
  std::optional<Eigen::Vector2d> touchedPoint(int sign) const;
  /// Books a motion's result into the state: modelled time, odometry, true clearance (leg: a
  /// forward motion).
  void noteMotion(const MotionResult& r, bool leg);
  /// How far the body can drive straight from `from` (a pose in the present base_link) along its x
  /// axis before the latest scan's band points obstruct it (leg_check), with what odometry cannot
  /// see by `bounds` (nullptr: the plain disc, as if odometry were exact since the scan); +inf
  /// without a scan to check against.
  /// blocking: the point that ends the free travel (present base_link), when it is finite.
  double freeTravel(const DeadReckoning* bounds, const Pose2D& from = Pose2D(),
                    Eigen::Vector2d* blocking = nullptr) const;
  /// Keeps a point (map frame) the leg check stopped a leg before as an obstruction for every later
  /// plan (MissionState::obstructions, disc contact_point_radius_m; one within that of a known one
  /// is known; the oldest goes beyond kMaxObstructions).
  void noteObstruction(const Eigen::Vector2d& point);
  static constexpr size_t kMaxObstructions = 100;
  /// The shortest sidestep (leg_sidestep_m) from the present pose after which the leg to `waypoint`
  /// (present base_link) is clear for `step` metres by the leg check: the offset in the present
  /// base_link, or nullopt.
  std::optional<Eigen::Vector2d> sidestep(const Eigen::Vector2d& waypoint, double step) const;
  /// The leg_check_min_points-th smallest distance of the latest scan's band points (carried to the
  /// present base_link by odometry) from the segment a-b of the present base_link [m]; +inf without.
  double distanceFromSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// The latest scan's base_link to the present one, by odometry (obstacles_odom_ -> odom now).
  Pose2D scanToPresent() const;
  /// The position bound of what odometry cannot see (dead_reckoning_) once the robot has turned
  /// towards `next` (map frame) from its estimate and driven there [m].
  double boundAfter(const Eigen::Vector2d& next) const;
  /// The turn before a leg along `delta` (map frame) from heading `yaw`, and whether the leg is
  /// then driven backwards (reverse_legs: the smaller of the two turns).
  struct LegTurn {
    double turn = 0.0;
    bool backwards = false;
  };
  LegTurn legTurn(const Eigen::Vector2d& delta, double yaw) const;
  bool contactBoundReached() const;
  bool checkControl();        ///< waits while paused; false when aborted
  void backoff(int attempt);  ///< waits attempt * retry_backoff_s (returns early on abort)
  void setState(State s);
  void notifyState();
  void event(const std::string& what, bool warning = false);
  void save();
  double elapsed() const;
  bool budgetReached() const;

  MissionConfig config_;
  RobotSystem& robot_;
  /// The latest scan's points in the body's height band (xy in its base_link) and the odometry
  /// pose they were taken at (the leg check).
  std::vector<Eigen::Vector2d> obstacles_;
  Pose2D obstacles_odom_;
  double leg_max_m_ = 0.0;        ///< the last plan's d_max (0: none yet: config_.d_max_m)
  DeadReckoning dead_reckoning_;  ///< what odometry cannot see since that scan (the leg check)
  Log info_, warn_;
  mutable std::mutex mutex_;
  std::condition_variable control_cv_;
  Control control_ = Control::Run;
  std::string end_reason_;  ///< set by end(): why run() ends Failed
  MissionState state_;
  double elapsed_at_start_ = 0.0;
  std::chrono::steady_clock::time_point started_;
  double pending_plan_wall_s_ = 0.0;
  std::function<void()> state_listener_;
  std::string built_mesh_;  ///< builtMesh()
};

}  // namespace mission
}  // namespace scanstop
