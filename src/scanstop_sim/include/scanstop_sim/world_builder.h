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

  /// Which side of a piece of furniture its back (sofa, bed's headboard, shelf's back panel) or
  /// its drawers (desk) are on: the side of larger y (North), larger x (East), ...
  enum class Side { North, East, South, West };
  /// A convex hexahedron from its bottom corners b[0..3] and top corners t[0..3], both counter-
  /// clockwise seen from above, t[i] above b[i] (slanted and overhanging parts).
  void hexahedron(const Eigen::Vector3d b[4], const Eigen::Vector3d t[4]);
  /// A desk over [x0, x1] x [y0, y1]: top at 0.75 m, a drawer block from the floor to the top on
  /// the `drawers` end (0.42 m of the long side), two thin legs at the other end.
  void desk(double x0, double y0, double x1, double y1, Side drawers);
  /// A sofa (or an armchair when short) over [x0, x1] x [y0, y1] with its back on `back`: short feet,
  /// a base recessed 0.15 m from the front, a seat at 0.45 m overhanging the base, a back up to
  /// 0.85 m, and arms that slope outwards from 0.45 m to 0.62 m and overhang the footprint of the
  /// feet by 0.12 m on each end (nothing on the floor below them; their undersides face away from
  /// a scanner at seat height).
  void sofa(double x0, double y0, double x1, double y1, Side back);
  /// An open shelf over [x0, x1] x [y0, y1] up to h: two thin side panels from the floor, boards
  /// every 0.35 m from `lowest` up (nothing but the side panels below the lowest board), a back panel.
  void shelf(double x0, double y0, double x1, double y1, double h, double lowest, Side back);
  /// A bed over [x0, x1] x [y0, y1]: four legs, a frame from 0.2 m, a mattress to 0.55 m overhanging
  /// the frame by 5 cm, a headboard to 1.0 m on `head`.
  void bed(double x0, double y0, double x1, double y1, Side head);
  /// A low coffee table: top w x d at 0.4 m on four thin legs.
  void coffeeTable(double cx, double cy, double w, double d);
  /// A floor lamp: a 2 cm base plate (below the robot's obstacle band), a 3 cm pole, a shade at 1.3-1.6 m.
  void floorLamp(double cx, double cy);
  /// Low clutter just above the floor band (a cable duct, a flat box): [x0, x1] x [y0, y1] up to h [m].
  void clutter(double x0, double y0, double x1, double y1, double h);

  const TriangleMesh& mesh() const { return mesh_; }

 private:
  void quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d);
  double height_;
  TriangleMesh mesh_;
};

/// One of the project's worlds.
struct WorldSpec {
  std::string name;  ///< file name without .stl
  std::string description;
  Eigen::Vector2d size_m;  ///< outer footprint
  Pose2D start;            ///< documented start pose (world frame)
  TriangleMesh mesh;
  std::string materials_yaml;  ///< the world's <name>.materials.yaml (materials.h); empty: none
};

/// room_10x8 (thesis chapter 8), office_loop, corridor, office_large (a 50 x 40 m office floor:
/// corridors with two loops, rooms on both sides, an open-plan area, furniture) and the furnished
/// worlds furnished_1..3 (furnishedWorld with seeds 1..3), and artifacts_room (the thesis' scanner
/// artifacts of chapter 8: a table with a retroreflective leg and an absorbing monitor, a door).
std::vector<WorldSpec> buildWorlds();

/// A furnished flat of four to six rooms, generated from `seed` (the same seed gives the same
/// world on every machine): rooms of random size on a grid, doors of 0.9-1.1 m between
/// neighbours, and in each room furniture of every kind real homes and offices have (tables with
/// thin legs and chairs pushed under them, desks with drawers, sofas and armchairs with
/// overhanging arms, open shelves, a bed, a coffee table, a floor lamp, low clutter) placed
/// along the walls with room to pass between pieces. Named "furnished_<seed>"; its start pose
/// lies in free space.
WorldSpec furnishedWorld(unsigned seed);

/// The documented start pose of a world by name (also "turtlebot3_house"); throws ConfigError.
Pose2D defaultStartPose(const std::string& world_name);

}  // namespace sim
}  // namespace scanstop
