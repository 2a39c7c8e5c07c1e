#pragma once
/// The explorer's state across planning steps: the growing floor grid, the scan positions (for
/// the knowledge map) and the blacklist of targets the robot failed to reach.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_explorer/floor_map.h"
#include "scanstop_explorer/planner.h"

namespace scanstop {
namespace explorer {

/// All explorer parameters.
struct ExplorerConfig {
  FloorConfig floor;
  PlannerConfig planner;
  /// Floor disc around each scan pose taken as floor where unknown: the scanner cannot see the floor
  /// under and near the robot (a 240 deg fan turned about the vertical axis misses a cone of
  /// half-angle 60 deg below it: radius = scanner height * tan(60 deg), 0.78 m at 0.45 m) [m], [0, 5]
  double known_free_radius_m = 0.8;
  double self_filter_radius_m =
      0.3;  ///< points closer than this to the scan pose (horizontally) are the robot itself [m], [0, 5]
  double target_tolerance_m = 0.3;  ///< robot this close to the last target: it was reached [m], (0, 10]
  double progress_m = 0.2;  ///< the travel distance to an unreached target must shrink by this per plan [m], [0, 10]
  int max_failed_attempts = 2;      ///< plans without progress before a target is blacklisted, [1, 100]
  double blacklist_radius_m = 0.5;  ///< radius of the blacklisted disc around a failed target [m], (0, 10]
  /// A contact (where the robot touched something the scans did not show as an obstacle) becomes an
  /// obstacle disc of this radius in every later plan, unless the caller gives the contact its own
  /// radius (the mission does for a contact located at a scanned point); the planner's inflation by
  /// robot_radius_m keeps every path off it [m], (0, 2]
  double contact_radius_m = 0.15;

  /// Validates every field (ConfigError naming parameter, value and range).
  void validate() const;
};

class Explorer {
 public:
  explicit Explorer(const ExplorerConfig& config = ExplorerConfig());

  /// Adds one registered scan: points in the map frame (z = 0 is the floor) [m], base_link pose
  /// in the map frame. Points within self_filter_radius_m of the pose are dropped (the robot's own
  /// body and the scanner's near-range noise). Each index is used once: returns false (and changes nothing) for an
  /// index that was added before.
  bool addScan(uint32_t index, const Pose2D& T_map_base, const std::vector<Eigen::Vector3f>& points_map);
  /// Adds every scan of a map directory that is not in yet. Returns how many were added. A scan
  /// file that cannot be read (missing, truncated, corrupt) is skipped and its problem, naming the
  /// file, appended to `problems` (when given); it is tried again on the next call.
  /// Scans already in take the directory's poses (updatePoses): after SLAM's relaxation moved
  /// them, the floor grid follows; `moved` (when given) receives how many scans moved.
  size_t loadMapDirectory(const MapDirectory& dir, std::vector<std::string>* problems = nullptr,
                          size_t* moved = nullptr);

  /// Corrected poses of scans already added (e.g. after SLAM's global relaxation; issue #17 point
  /// 3): when any of them moved farther than tol_m [m] or tol_rad [rad] from the pose it was added
  /// at, every scan takes its new pose and the floor grid is rebuilt from the scans' points (kept in
  /// base_link, floor and obstacle layers only), so that floor, obstacles and known-free discs lie
  /// where the corrected map has them. Indices not added are ignored; contacts and the blacklist
  /// stay where they are (map frame). Returns how many scans moved beyond the tolerance (0: nothing
  /// changed).
  size_t updatePoses(const std::map<uint32_t, Pose2D>& poses, double tol_m = 0.005, double tol_rad = 0.1 * M_PI / 180);
  /// The pose each scan is in the floor grid at.
  Pose2D scanPose(uint32_t index) const { return scans_.at(index).pose; }

  /// One planning step from the robot's map-frame pose; updates the blacklist (a target planned
  /// before that the robot neither reached nor got closer to max_failed_attempts times).
  /// With a goal: the path to the reached cell nearest to it instead of a new scan location
  /// (PlanInput::goal; it does not count as an attempt at the previous target).
  PlanResult plan(const Pose2D& T_map_base, const std::optional<Eigen::Vector2d>& goal = std::nullopt);

  /// Grows the floor grid to hold the map-frame box [lo, hi] [m] (plus the margin) before any scan
  /// reaches it, e.g. a known building outline; cells stay unknown.
  void reserveArea(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) { floor_.ensureContains(lo, hi); }

  /// Excludes a disc from all future targets and from the termination test.
  void blacklist(const Eigen::Vector2d& center_map, double radius_m);
  /// A target the caller failed to reach: blacklists a disc of blacklist_radius_m around it unless
  /// that point is blacklisted already. Returns true when it was new.
  bool markUnreachable(const Eigen::Vector2d& target_map);
  const std::vector<std::pair<Eigen::Vector2d, double>>& blacklisted() const { return blacklist_; }
  /// A point the robot touched (map frame): from now on an obstacle disc of radius_m (0:
  /// contact_radius_m) in the floor grid of every plan, whatever the scans show there. Returns false
  /// (nothing changed) for a non-finite point, a negative or non-finite radius, or a point within
  /// 1 cm of a known contact.
  bool addContact(const Eigen::Vector2d& point_map, double radius_m = 0.0);
  /// The contacts with the radius of their discs [m].
  const std::vector<std::pair<Eigen::Vector2d, double>>& contacts() const { return contacts_; }

  size_t scanCount() const { return scans_.size(); }
  bool hasScan(uint32_t index) const { return scans_.count(index) > 0; }
  std::vector<Eigen::Vector2d> scanPositions() const;
  const FloorMap& floorMap() const { return floor_; }
  const ExplorerConfig& config() const { return config_; }

 private:
  struct Attempt {
    bool active = false;
    Eigen::Vector2d target = Eigen::Vector2d::Zero();
    double cost_m = 0.0;
    int failures = 0;
  };
  ExplorerConfig config_;
  FloorMap floor_;
  /// One scan as the floor grid holds it: its pose and its floor- and obstacle-layer points in
  /// base_link (after the self filter), for rebuilding the grid when poses move.
  struct Scan {
    Pose2D pose;
    std::vector<Eigen::Vector3f> points_base;
  };
  void addToFloor(const Scan& scan);
  std::map<uint32_t, Scan> scans_;
  std::vector<std::pair<Eigen::Vector2d, double>> blacklist_;
  std::vector<std::pair<Eigen::Vector2d, double>> contacts_;  ///< (point [m], disc radius [m])
  Attempt last_;
};

}  // namespace explorer
}  // namespace scanstop
