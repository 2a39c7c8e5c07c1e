#pragma once
/// Builds the project's own simulated worlds from boxes (walls with door openings, floors,
/// ceilings, furniture), reproducibly: `make_worlds` writes them to worlds/, a test checks the
/// committed STLs equal a fresh build.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"

namespace scanstop {
namespace sim {

/// Accumulates boxes and rectangles into one mesh with outward-facing triangles.
class WorldBuilder {
 public:
  static constexpr double kWallThickness = 0.1;
  static constexpr double kDoorHeight = 2.0;

  explicit WorldBuilder(double height_m) : height_(height_m) {}

  /// An axis-aligned box [lo, hi].
  void box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  /// Floor (facing up at z = 0) and ceiling (facing down at the height) over [x0, x1] x [y0, y1].
  void floorAndCeiling(double x0, double y0, double x1, double y1);
  /// A wall along y = y from x0 to x1 (centred on the line), with door openings [a, b] along x.
  void wallX(double y, double x0, double x1, std::vector<std::pair<double, double>> doors = {});
  /// A wall along x = x from y0 to y1, with door openings along y.
  void wallY(double x, double y0, double y1, std::vector<std::pair<double, double>> doors = {});
  /// A table: top of w x d at 0.72 m, four thin legs (4 cm).
  void table(double cx, double cy, double w, double d);
  /// A chair: seat at 0.45 m, thin legs, a backrest on the side facing `back_yaw`.
  void chair(double cx, double cy, double back_yaw);
  /// A closed cabinet.
  void cabinet(double x0, double y0, double x1, double y1, double h);

  const TriangleMesh& mesh() const { return mesh_; }

 private:
  void quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d);
  double height_;
  TriangleMesh mesh_;
};

/// One of the project's worlds.
struct WorldSpec {
  std::string name;         ///< file name without .stl
  std::string description;
  Eigen::Vector2d size_m;   ///< outer footprint
  Pose2D start;             ///< documented start pose (world frame)
  TriangleMesh mesh;
};

/// room_10x8 (thesis chapter 8), office_loop, corridor.
std::vector<WorldSpec> buildWorlds();

/// The documented start pose of a world by name (also "turtlebot3_house"); throws ConfigError.
Pose2D defaultStartPose(const std::string& world_name);

}  // namespace sim
}  // namespace scanstop
