#include "scanstop_sim/world_builder.h"

#include <algorithm>
#include <cmath>

#include "scanstop_common/error.h"

namespace scanstop {
namespace sim {

void WorldBuilder::quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                        const Eigen::Vector3d& d) {
  const int base = static_cast<int>(mesh_.vertices.size());
  for (const auto* v : {&a, &b, &c, &d}) mesh_.vertices.push_back(v->cast<float>());
  mesh_.faces.emplace_back(base, base + 1, base + 2);
  mesh_.faces.emplace_back(base, base + 2, base + 3);
}

void WorldBuilder::box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const double x0 = lo.x(), y0 = lo.y(), z0 = lo.z(), x1 = hi.x(), y1 = hi.y(), z1 = hi.z();
  if (x1 <= x0 || y1 <= y0 || z1 <= z0) return;
  using V = Eigen::Vector3d;
  quad(V(x0, y0, z0), V(x0, y1, z0), V(x1, y1, z0), V(x1, y0, z0));  // bottom (-z)
  quad(V(x0, y0, z1), V(x1, y0, z1), V(x1, y1, z1), V(x0, y1, z1));  // top (+z)
  quad(V(x0, y0, z0), V(x1, y0, z0), V(x1, y0, z1), V(x0, y0, z1));  // -y
  quad(V(x0, y1, z0), V(x0, y1, z1), V(x1, y1, z1), V(x1, y1, z0));  // +y
  quad(V(x0, y0, z0), V(x0, y0, z1), V(x0, y1, z1), V(x0, y1, z0));  // -x
  quad(V(x1, y0, z0), V(x1, y1, z0), V(x1, y1, z1), V(x1, y0, z1));  // +x
}

void WorldBuilder::floorAndCeiling(double x0, double y0, double x1, double y1) {
  using V = Eigen::Vector3d;
  quad(V(x0, y0, 0), V(x1, y0, 0), V(x1, y1, 0), V(x0, y1, 0));
  quad(V(x0, y0, height_), V(x0, y1, height_), V(x1, y1, height_), V(x1, y0, height_));
}

void WorldBuilder::wallX(double y, double x0, double x1, std::vector<std::pair<double, double>> doors) {
  std::sort(doors.begin(), doors.end());
  const double t = kWallThickness / 2;
  double x = x0;
  for (const auto& [a, b] : doors) {
    box({x, y - t, 0}, {a, y + t, height_});
    box({a, y - t, kDoorHeight}, {b, y + t, height_});  // lintel
    x = b;
  }
  box({x, y - t, 0}, {x1, y + t, height_});
}

void WorldBuilder::wallY(double x, double y0, double y1, std::vector<std::pair<double, double>> doors) {
  std::sort(doors.begin(), doors.end());
  const double t = kWallThickness / 2;
  double y = y0;
  for (const auto& [a, b] : doors) {
    box({x - t, y, 0}, {x + t, a, height_});
    box({x - t, a, kDoorHeight}, {x + t, b, height_});
    y = b;
  }
  box({x - t, y, 0}, {x + t, y1, height_});
}

void WorldBuilder::table(double cx, double cy, double w, double d) {
  const double top = 0.72, thick = 0.03, leg = 0.04;
  box({cx - w / 2, cy - d / 2, top - thick}, {cx + w / 2, cy + d / 2, top});
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      const double lx = cx + sx * (w / 2 - 0.05), ly = cy + sy * (d / 2 - 0.05);
      box({lx - leg / 2, ly - leg / 2, 0}, {lx + leg / 2, ly + leg / 2, top - thick});
    }
}

void WorldBuilder::chair(double cx, double cy, double back_yaw) {
  const double s = 0.44, seat = 0.45, leg = 0.03;
  box({cx - s / 2, cy - s / 2, seat - 0.03}, {cx + s / 2, cy + s / 2, seat});
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      const double lx = cx + sx * (s / 2 - 0.03), ly = cy + sy * (s / 2 - 0.03);
      box({lx - leg / 2, ly - leg / 2, 0}, {lx + leg / 2, ly + leg / 2, seat - 0.03});
    }
  // Backrest on the side of back_yaw (rounded to the nearest axis).
  const int q = static_cast<int>(std::lround(back_yaw / (M_PI / 2))) & 3;
  const double bx = q == 0 ? 1 : q == 2 ? -1 : 0, by = q == 1 ? 1 : q == 3 ? -1 : 0;
  const double px = cx + bx * (s / 2 - 0.02), py = cy + by * (s / 2 - 0.02);
  const double hx = bx != 0 ? 0.02 : s / 2, hy = by != 0 ? 0.02 : s / 2;
  box({px - hx, py - hy, seat}, {px + hx, py + hy, 0.9});
}

void WorldBuilder::cabinet(double x0, double y0, double x1, double y1, double h) { box({x0, y0, 0}, {x1, y1, h}); }

namespace {

WorldSpec room10x8() {
  // Thesis chapter 8: a room of about 10 x 8 m with a door in the lower left corner leading out;
  // tables with thin legs, chairs, a cabinet. Interior x in [0, 10], y in [0, 8]; a 2 m wide
  // corridor runs along the south side behind the door.
  WorldBuilder b(2.5);
  const double t = WorldBuilder::kWallThickness / 2;
  b.floorAndCeiling(-t - 0.5, -2.2 - t - 0.5, 10 + t + 0.5, 8 + t + 0.5);
  b.wallX(8 + t, -2 * t, 10 + 2 * t);                      // north
  b.wallX(-t, -2 * t, 10 + 2 * t, {{0.4, 1.3}});          // south, with the door (0.9 m wide)
  b.wallY(-t, -2.2 - 2 * t, 8 + 2 * t);                    // west (room and corridor)
  b.wallY(10 + t, -2.2 - 2 * t, 8 + 2 * t);                // east
  b.wallX(-2.2 - t, -2 * t, 10 + 2 * t);                   // corridor's south wall
  // Furniture.
  b.table(6.0, 5.0, 1.6, 0.8);
  b.chair(6.0, 4.2, -M_PI / 2);
  b.chair(6.0, 5.8, M_PI / 2);
  b.table(3.0, 2.2, 1.2, 0.8);
  b.chair(3.0, 1.4, -M_PI / 2);
  b.chair(2.0, 2.2, M_PI);
  b.cabinet(8.9, 6.4, 9.95, 7.95, 1.8);
  b.cabinet(0.05, 6.0, 0.55, 7.5, 1.2);
  return {"room_10x8", "thesis chapter 8: 10 x 8 x 2.5 m room, door in the south-west corner to a 2 m corridor, "
                       "two tables with thin legs, four chairs, two cabinets",
          {10.2, 10.5}, Pose2D(2.0, 5.0, 0.0), b.mesh()};
}

WorldSpec officeLoop() {
  // An office floor of 18 x 14 m: a corridor loop (2 m wide) around a central meeting room, with
  // offices north and south of it; doors everywhere, so loops and doors matter.
  WorldBuilder b(2.6);
  const double t = WorldBuilder::kWallThickness / 2;
  b.floorAndCeiling(-0.5, -0.5, 18.5, 14.5);
  b.wallX(0, 0, 18);
  b.wallX(14, 0, 18);
  b.wallY(0, 0, 14);
  b.wallY(18, 0, 14);
  // Corridor ring between the outer rectangle [3, 15] x [3, 11] and the inner [5, 13] x [5, 9].
  b.wallX(3, 0, 18, {{1.0, 2.0}, {7.0, 8.0}, {12.0, 13.0}});   // offices south: doors
  b.wallX(11, 0, 18, {{4.0, 5.0}, {9.0, 10.0}, {15.5, 16.5}}); // offices north
  b.wallY(3, 3 + t, 11 - t, {{6.5, 7.5}});                    // west office
  b.wallY(15, 3 + t, 11 - t, {{6.5, 7.5}});                   // east office
  // Central meeting room with one door; the corridor runs around it.
  b.wallX(5, 5, 13, {{8.5, 9.5}});
  b.wallX(9, 5, 13);
  b.wallY(5, 5 - t, 9 + t);
  b.wallY(13, 5 - t, 9 + t);
  // Partitions between the offices.
  b.wallY(6, 0, 3 - t);
  b.wallY(11, 0, 3 - t);
  b.wallY(7, 11 + t, 14);
  b.wallY(12.5, 11 + t, 14);
  // Corridor openings into the west/east ends of the ring: the ring is closed by the offices.
  b.table(9.0, 7.0, 2.0, 1.0);
  b.chair(8.3, 6.2, -M_PI / 2);
  b.chair(9.7, 7.8, M_PI / 2);
  b.table(3.0, 1.5, 1.4, 0.7);
  b.table(14.0, 12.5, 1.4, 0.7);
  b.cabinet(0.05, 12.5, 0.6, 13.95, 1.8);
  return {"office_loop", "18 x 14 m office floor: a 2 m corridor loop around a meeting room, offices on all sides",
          {18.0, 14.0}, Pose2D(4.0, 7.0, M_PI / 2), b.mesh()};
}

WorldSpec corridor() {
  // A 30 m corridor (2 m wide) with 4 x 4 m side rooms alternating north and south.
  WorldBuilder b(2.5);
  b.floorAndCeiling(-0.5, -4.5, 30.5, 6.5);
  b.wallY(0, 0, 2);
  b.wallY(30, 0, 2);
  std::vector<std::pair<double, double>> south_doors, north_doors;
  for (int i = 0; i < 6; ++i) {
    const double x0 = 1.0 + 5.0 * i;
    if (i % 2 == 0) {
      south_doors.push_back({x0 + 1.5, x0 + 2.5});
      b.wallY(x0, -4, 0);
      b.wallY(x0 + 4, -4, 0);
      b.wallX(-4, x0, x0 + 4);
      b.table(x0 + 2, -2.5, 1.2, 0.7);
    } else {
      north_doors.push_back({x0 + 1.5, x0 + 2.5});
      b.wallY(x0, 2, 6);
      b.wallY(x0 + 4, 2, 6);
      b.wallX(6, x0, x0 + 4);
      b.cabinet(x0 + 0.1, 5.4, x0 + 1.2, 5.95, 1.6);
    }
  }
  // The corridor walls with the room doors (room walls close each room).
  b.wallX(0, 0, 30, south_doors);
  b.wallX(2, 0, 30, north_doors);
  return {"corridor", "30 x 2 m corridor with six 4 x 4 m side rooms (three each side)", {30.0, 10.0},
          Pose2D(1.0, 1.0, 0.0), b.mesh()};
}

}  // namespace

std::vector<WorldSpec> buildWorlds() { return {room10x8(), officeLoop(), corridor()}; }

Pose2D defaultStartPose(const std::string& world_name) {
  for (const WorldSpec& w : buildWorlds())
    if (w.name == world_name) return w.start;
  // The real house from ../shared/data/worlds: its living room.
  if (world_name == "turtlebot3_house") return Pose2D(-3.0, 1.0, 0.0);
  throw ConfigError("no documented start pose for world '" + world_name +
                    "' (known: room_10x8, office_loop, corridor, turtlebot3_house); give start_pose");
}

}  // namespace sim
}  // namespace scanstop
