#pragma once
/// The simulated robot: a Pioneer-like disc on the flat floor of a World, with the rotating URG,
/// the thesis' error models, collision detection and a modelled clock. ROS-free; sim_node and the
/// scan_world tool wrap it.
///
/// Frames: the world's frame (`world`); the start pose defines `map` and the odometry origin, so
/// odometry and ground truth are both expressed relative to the start pose.

#include <cstdint>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"
#include "scanstop_common/scan_filter.h"
#include "scanstop_sim/models.h"
#include "scanstop_sim/world.h"

namespace scanstop {
namespace sim {

struct SimConfig {
  ScannerConfig scanner;
  ErrorProfile errors;
  double robot_radius_m = 0.26;        ///< collision disc (Pioneer 2 DX: 44.5 x 38 cm body, 0.26 m swept radius)
  double collision_step_m = 0.005;     ///< path sampling for collision checks [m]
  double max_forward_m = 5.0;          ///< longest forward command accepted [m]
  double max_rotate_rad = 2.0 * M_PI;  ///< largest rotation command accepted [rad]
  bool outlier_filter = true;          ///< apply the thesis 3.4 filter to every scan, as the real driver does
  uint64_t seed = 1;
  /// Throws ConfigError naming sim_node's parameter; `profile_prefix` names the error profile's
  /// parameters (e.g. "profiles/thesis/").
  void validate(const std::string& profile_prefix = "") const;
};

/// Checks of the service requests, made before anything is applied. Each returns an empty string
/// when the request is fine, otherwise what is wrong in words for the response's message.
/// TakeScan.planes: one of 50, 100, 200, 400.
std::string checkScanPlanes(long planes);
/// Rotate.angle_rad: finite, |angle| <= max_rotate_rad.
std::string checkRotation(double angle_rad, double max_rotate_rad);
/// Forward.distance_m: finite, |distance| <= max_forward_m.
std::string checkForward(double distance_m, double max_forward_m);
/// A (re)start pose in the world frame: finite, yaw within [-2 pi, 2 pi], the robot disc inside the
/// world's bounding box and not touching an obstacle.
std::string checkStartPose(const Pose2D& pose_in_world, const World& world, double robot_radius_m);

/// Simulator::restoreState was given the state of another world (by the world file's name).
class StateOfAnotherWorld : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct ScanOutput {
  PointCloud cloud;  ///< organized: height = planes, width = beams; base_link frame; NaN invalid
  uint32_t raw_points = 0;
  uint32_t valid_points = 0;
  uint32_t planes_dropped = 0;
  uint32_t outliers_removed = 0;
  uint32_t mixed_pixels = 0;            ///< readings mixed from surfaces at different depths (scanner.mixed_pixels)
  uint32_t mixed_pixel_candidates = 0;  ///< beams that cast sub-rays (a neighbour off their surface)
  double duration_s = 0.0;              ///< modelled
};

/// How far MotionOutput::min_clearance_m is measured [m].
constexpr double kClearanceRange = 1.0;

struct MotionOutput {
  double achieved = 0.0;  ///< as odometry measured it: [m] or [rad]
  bool collision = false;
  double duration_s = 0.0;  ///< modelled
  /// Ground truth: the smallest distance between the robot's body (the robot_radius disc) and the
  /// world's obstacles along the motion (every true pose it passed), measured up to
  /// kClearanceRange (that value: at least as far); 0 at a contact [m].
  double min_clearance_m = 0.0;
};

/// The simulation's start-up checks, in the order that names the right cause (issue 22): the world
/// file (missing, not an STL, no floor: IoError naming the file and the problem), then the start
/// pose (`start_text` "x,y,yaw"; empty: the documented start pose of the world file's stem):
/// ConfigError naming `start_param` for garbage text, a world without a documented start pose, a
/// pose outside the world or inside an obstacle. Returns the checked simulator; `start_out` (if
/// given) receives the start pose.
std::unique_ptr<class Simulator> makeSimulator(const std::string& world_path, const WorldOptions& world_options,
                                               const SimConfig& config, const std::string& start_text,
                                               const std::string& start_param = "start_pose",
                                               Pose2D* start_out = nullptr);

/// Makes glibc keep the scan-sized buffers (cloud, PointCloud2, serialized message: ~5 MB each for
/// 400 planes) in the heap instead of mapping and unmapping them for every scan: on this
/// (virtualized) machine the page faults of fresh mappings cost more than the ray casting
/// (sim_bench: scan + PointCloud2 + serialization 140-170 ms before, 55-70 ms after). Call once at
/// program start; sim_node, sim_bench and scan_world do.
void keepLargeBuffersMapped();

class Simulator {
 public:
  /// Throws ConfigError for a bad config and std::invalid_argument for a start pose in collision.
  Simulator(World world, SimConfig config, const Pose2D& start_in_world);

  /// Takes a full 3D scan (planes in {50, 100, 200, 400} or any 1..2000). Throws std::invalid_argument.
  ScanOutput scan(int planes);
  /// Drives straight ahead by distance_m (true motion through the error model, stops at contact).
  /// Throws std::invalid_argument (checkForward's message) and changes nothing for a bad distance.
  MotionOutput forward(double distance_m);
  /// Turns on the spot by angle_rad. Throws std::invalid_argument (checkRotation) for a bad angle.
  MotionOutput rotate(double angle_rad);
  /// Puts the robot at a new start pose; odometry and the map frame restart there. seed < 0 keeps the RNG.
  /// Throws std::invalid_argument (checkStartPose's message) and changes nothing for a bad pose.
  void reset(const Pose2D& start_in_world, int64_t seed);

  /// The state that evolves while the simulation runs (start, true pose, odometry, clock, scan
  /// counter, the random generator's state) as text, so that a restarted sim_node continues where
  /// the dead one stopped: the same robot pose and the same random sequence.
  std::string saveState() const;
  /// Restores a saveState() text of the same world. Throws std::invalid_argument naming what is
  /// wrong (format, a missing or non-finite field, a pose outside the world or in an obstacle) and
  /// changes nothing then.
  void restoreState(const std::string& text);

  /// An obstacle the scanner cannot see (glass, a person stepping in, a test's forced contact): a
  /// vertical cylinder at (x, y) in the world frame, radius [m], that stops the robot and enters its
  /// true clearance like the world's geometry, while rays pass through it. Kept in saveState().
  struct HiddenObstacle {
    double x = 0.0, y = 0.0, radius = 0.0;
  };
  /// Adds one. Throws std::invalid_argument (and adds nothing) for a non-finite centre, a radius
  /// outside (0, 2] m, or one that would touch the robot where it stands now.
  void addHiddenObstacle(const HiddenObstacle& obstacle);
  const std::vector<HiddenObstacle>& hiddenObstacles() const { return hidden_; }

  const Pose2D& trueInWorld() const { return true_world_; }
  /// Ground truth in the map frame (relative to the start pose).
  Pose2D trueInMap() const { return start_.inverse() * true_world_; }
  const Pose2D& odometry() const { return odom_; }
  const Pose2D& start() const { return start_; }
  double clock() const { return clock_s_; }
  const World& world() const { return world_; }
  const SimConfig& config() const { return config_; }

 private:
  World world_;
  SimConfig config_;
  Pose2D start_, true_world_, odom_;
  std::mt19937_64 rng_;
  uint64_t scan_counter_ = 0;
  double clock_s_ = 0.0;
  std::vector<HiddenObstacle> hidden_;

  /// The body's disc at p touches the world's obstacle map or a hidden obstacle.
  bool bodyCollides(const Eigen::Vector2d& p) const;
  /// The body's true clearance at p (world and hidden obstacles), searched out to kClearanceRange [m].
  double bodyClearance(const Eigen::Vector2d& p) const;
};

}  // namespace sim
}  // namespace scanstop
