#include "scanstop_sim/world_builder.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

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

void WorldBuilder::hexahedron(const Eigen::Vector3d b[4], const Eigen::Vector3d t[4]) {
  quad(b[0], b[3], b[2], b[1]);  // bottom, seen from below
  quad(t[0], t[1], t[2], t[3]);  // top
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    quad(b[i], b[j], t[j], t[i]);
  }
}

namespace {

/// A piece of furniture's own frame: u across its width, v from its front (0) to its back (depth),
/// mapped onto the world rectangle [x0, x1] x [y0, y1] by a rotation of 0, 90, 180 or 270 deg so
/// that the back lies on `back`.
struct Local {
  double x0, y0, x1, y1;
  WorldBuilder::Side back;
  double width() const {
    return back == WorldBuilder::Side::North || back == WorldBuilder::Side::South ? x1 - x0 : y1 - y0;
  }
  double depth() const {
    return back == WorldBuilder::Side::North || back == WorldBuilder::Side::South ? y1 - y0 : x1 - x0;
  }
  Eigen::Vector3d at(double u, double v, double z) const {
    switch (back) {
      case WorldBuilder::Side::North:
        return {x0 + u, y0 + v, z};
      case WorldBuilder::Side::South:
        return {x1 - u, y1 - v, z};
      case WorldBuilder::Side::East:
        return {x0 + v, y1 - u, z};
      case WorldBuilder::Side::West:
        return {x1 - v, y0 + u, z};
    }
    return {x0 + u, y0 + v, z};
  }
  /// An axis-aligned box given in the local frame.
  void box(WorldBuilder& b, double u0, double v0, double u1, double v1, double z0, double z1) const {
    const Eigen::Vector3d p = at(u0, v0, z0), q = at(u1, v1, z1);
    b.box(p.cwiseMin(q), p.cwiseMax(q));
  }
};

}  // namespace

void WorldBuilder::desk(double x0, double y0, double x1, double y1, Side drawers) {
  // The drawers' end is the local "back": the desk's long side runs across v.
  const Local l{x0, y0, x1, y1, drawers};
  const double W = l.width(), D = l.depth(), top = 0.75, thick = 0.03, leg = 0.04;
  l.box(*this, 0, 0, W, D, top - thick, top);
  l.box(*this, 0.01, D - 0.42, W - 0.01, D, 0, top - thick);  // drawer block
  for (const double u : {0.03, W - 0.03 - leg}) l.box(*this, u, 0.03, u + leg, 0.03 + leg, 0, top - thick);
}

void WorldBuilder::sofa(double x0, double y0, double x1, double y1, Side back) {
  const Local l{x0, y0, x1, y1, back};
  const double W = l.width(), D = l.depth();
  const double overhang = 0.12, arm = 0.18, recess = 0.15, foot = 0.05;
  for (const double u : {overhang, W - overhang - foot})
    for (const double v : {recess, D - foot}) l.box(*this, u, v, u + foot, v + foot, 0, 0.1);
  l.box(*this, overhang, recess, W - overhang, D, 0.1, 0.3);    // base
  l.box(*this, arm, 0, W - arm, D - 0.2, 0.3, 0.45);            // seat, overhanging the base's front
  l.box(*this, overhang, D - 0.2, W - overhang, D, 0.3, 0.85);  // back
  // Arms: the underside slopes from 0.3 m at the seat to 0.5 m at the outer edge.
  for (const bool left : {true, false}) {
    const double ui = left ? arm : W - arm, uo = left ? 0.0 : W;
    Eigen::Vector3d b[4], t[4];
    const double ua = left ? uo : ui, ub = left ? ui : uo;  // ua < ub
    const double za = left ? 0.5 : 0.3, zb = left ? 0.3 : 0.5;
    b[0] = l.at(ua, 0, za);
    b[1] = l.at(ub, 0, zb);
    b[2] = l.at(ub, D, zb);
    b[3] = l.at(ua, D, za);
    for (int i = 0; i < 4; ++i) t[i] = Eigen::Vector3d(b[i].x(), b[i].y(), 0.62);
    hexahedron(b, t);
  }
}

void WorldBuilder::shelf(double x0, double y0, double x1, double y1, double h, double lowest, Side back) {
  const Local l{x0, y0, x1, y1, back};
  const double W = l.width(), D = l.depth(), panel = 0.02;
  l.box(*this, 0, 0, panel, D, 0, h);
  l.box(*this, W - panel, 0, W, D, 0, h);
  for (double z = lowest; z + panel <= h - panel; z += 0.35) l.box(*this, panel, 0, W - panel, D, z, z + panel);
  l.box(*this, panel, 0, W - panel, D, h - panel, h);
  l.box(*this, panel, D - 0.01, W - panel, D, lowest, h - panel);  // back panel
}

void WorldBuilder::bed(double x0, double y0, double x1, double y1, Side head) {
  const Local l{x0, y0, x1, y1, head};
  const double W = l.width(), D = l.depth(), leg = 0.05;
  for (const double u : {0.05, W - 0.05 - leg})
    for (const double v : {0.05, D - 0.1 - leg}) l.box(*this, u, v, u + leg, v + leg, 0, 0.2);
  l.box(*this, 0.05, 0.05, W - 0.05, D - 0.1, 0.2, 0.35);  // frame
  l.box(*this, 0, 0, W, D - 0.05, 0.35, 0.55);             // mattress, overhanging the frame
  l.box(*this, 0, D - 0.05, W, D, 0, 1.0);                 // headboard
}

void WorldBuilder::coffeeTable(double cx, double cy, double w, double d) {
  const double top = 0.4, thick = 0.03, leg = 0.035;
  box({cx - w / 2, cy - d / 2, top - thick}, {cx + w / 2, cy + d / 2, top});
  for (const double sx : {-1.0, 1.0})
    for (const double sy : {-1.0, 1.0}) {
      const double lx = cx + sx * (w / 2 - 0.04), ly = cy + sy * (d / 2 - 0.04);
      box({lx - leg / 2, ly - leg / 2, 0}, {lx + leg / 2, ly + leg / 2, top - thick});
    }
}

void WorldBuilder::floorLamp(double cx, double cy) {
  box({cx - 0.15, cy - 0.15, 0}, {cx + 0.15, cy + 0.15, 0.02});
  box({cx - 0.015, cy - 0.015, 0.02}, {cx + 0.015, cy + 0.015, 1.3});
  box({cx - 0.2, cy - 0.2, 1.3}, {cx + 0.2, cy + 0.2, 1.6});
}

void WorldBuilder::clutter(double x0, double y0, double x1, double y1, double h) { box({x0, y0, 0}, {x1, y1, h}); }

namespace {

WorldSpec room10x8() {
  // Thesis chapter 8: a room of about 10 x 8 m with a door in the lower left corner leading out;
  // tables with thin legs, chairs, a cabinet. Interior x in [0, 10], y in [0, 8]; a 2 m wide
  // corridor runs along the south side behind the door.
  WorldBuilder b(2.5);
  const double t = WorldBuilder::kWallThickness / 2;
  b.floorAndCeiling(-t - 0.5, -2.2 - t - 0.5, 10 + t + 0.5, 8 + t + 0.5);
  b.wallX(8 + t, -2 * t, 10 + 2 * t);             // north
  b.wallX(-t, -2 * t, 10 + 2 * t, {{0.4, 1.3}});  // south, with the door (0.9 m wide)
  b.wallY(-t, -2.2 - 2 * t, 8 + 2 * t);           // west (room and corridor)
  b.wallY(10 + t, -2.2 - 2 * t, 8 + 2 * t);       // east
  b.wallX(-2.2 - t, -2 * t, 10 + 2 * t);          // corridor's south wall
  // Furniture.
  b.table(6.0, 5.0, 1.6, 0.8);
  b.chair(6.0, 4.2, -M_PI / 2);
  b.chair(6.0, 5.8, M_PI / 2);
  b.table(3.0, 2.2, 1.2, 0.8);
  b.chair(3.0, 1.4, -M_PI / 2);
  b.chair(2.0, 2.2, M_PI);
  b.cabinet(8.9, 6.4, 9.95, 7.95, 1.8);
  b.cabinet(0.05, 6.0, 0.55, 7.5, 1.2);
  return {"room_10x8",
          "thesis chapter 8: 10 x 8 x 2.5 m room, door in the south-west corner to a 2 m corridor, "
          "two tables with thin legs, four chairs, two cabinets",
          {10.2, 10.5},
          Pose2D(2.0, 5.0, 0.0),
          b.mesh(),
          ""};
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
  b.wallX(3, 0, 18, {{1.0, 2.0}, {7.0, 8.0}, {12.0, 13.0}});    // offices south: doors
  b.wallX(11, 0, 18, {{4.0, 5.0}, {9.0, 10.0}, {15.5, 16.5}});  // offices north
  b.wallY(3, 3 + t, 11 - t, {{6.5, 7.5}});                      // west office
  b.wallY(15, 3 + t, 11 - t, {{6.5, 7.5}});                     // east office
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
          {18.0, 14.0},  Pose2D(4.0, 7.0, M_PI / 2),
          b.mesh(),      ""};
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
  return {"corridor",   "30 x 2 m corridor with six 4 x 4 m side rooms (three each side)",
          {30.0, 10.0}, Pose2D(1.0, 1.0, 0.0),
          b.mesh(),     ""};
}

/// splitmix64: the same numbers from the same seed on every machine and standard library
/// (std::uniform_real_distribution is not specified bit for bit).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ULL + 0x2545F4914F6CDD1DULL) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double a, double b) { return a + (b - a) * static_cast<double>(next() >> 11) * 0x1.0p-53; }
  int integer(int a, int b) { return a + static_cast<int>(next() % static_cast<uint64_t>(b - a + 1)); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }

 private:
  uint64_t state_;
};

/// An axis-aligned rectangle of the floor plan [m].
struct Rect {
  double x0, y0, x1, y1;
  bool overlaps(const Rect& o, double gap) const {
    return x0 - gap < o.x1 && o.x0 - gap < x1 && y0 - gap < o.y1 && o.y0 - gap < y1;
  }
};

/// Places furniture in one room so that pieces keep `gap` from each other (room to pass) and stay
/// out of the doors' approaches and the keep-out areas.
class RoomFurnisher {
 public:
  RoomFurnisher(WorldBuilder& b, Rng& rng, const Rect& room, std::vector<Rect> keep_out)
      : b_(b), rng_(rng), room_(room), taken_(std::move(keep_out)) {}

  /// A rectangle of w (along the wall) x d (into the room) against a random wall, its back to the
  /// wall; false when none fits in 200 tries.
  bool againstWall(double w, double d, Rect& out, WorldBuilder::Side& back) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      const int wall = rng_.integer(0, 3);
      const double m = 0.03;  // off the wall's face
      Rect r;
      if (wall == 0 || wall == 2) {  // north / south wall: w along x
        if (room_.x1 - room_.x0 < w + 2 * m) continue;
        const double x = rng_.uniform(room_.x0 + m, room_.x1 - m - w);
        r = wall == 0 ? Rect{x, room_.y1 - m - d, x + w, room_.y1 - m} : Rect{x, room_.y0 + m, x + w, room_.y0 + m + d};
        back = wall == 0 ? WorldBuilder::Side::North : WorldBuilder::Side::South;
      } else {  // east / west wall: w along y
        if (room_.y1 - room_.y0 < w + 2 * m) continue;
        const double y = rng_.uniform(room_.y0 + m, room_.y1 - m - w);
        r = wall == 1 ? Rect{room_.x1 - m - d, y, room_.x1 - m, y + w} : Rect{room_.x0 + m, y, room_.x0 + m + d, y + w};
        back = wall == 1 ? WorldBuilder::Side::East : WorldBuilder::Side::West;
      }
      if (free(r)) {
        taken_.push_back(r);
        out = r;
        return true;
      }
    }
    return false;
  }
  /// A rectangle of w x d anywhere in the room (at least `wall_gap` from the walls).
  bool anywhere(double w, double d, double wall_gap, Rect& out) {
    for (int attempt = 0; attempt < 200; ++attempt) {
      const bool turn = rng_.chance(0.5);
      const double ww = turn ? d : w, dd = turn ? w : d;
      if (room_.x1 - room_.x0 < ww + 2 * wall_gap || room_.y1 - room_.y0 < dd + 2 * wall_gap) continue;
      const double x = rng_.uniform(room_.x0 + wall_gap, room_.x1 - wall_gap - ww);
      const double y = rng_.uniform(room_.y0 + wall_gap, room_.y1 - wall_gap - dd);
      const Rect r{x, y, x + ww, y + dd};
      if (free(r)) {
        taken_.push_back(r);
        out = r;
        return true;
      }
    }
    return false;
  }

  void sofa(double length) {
    Rect r;
    WorldBuilder::Side back;
    if (againstWall(length, 0.9, r, back)) b_.sofa(r.x0, r.y0, r.x1, r.y1, back);
  }
  void shelf() {
    Rect r;
    WorldBuilder::Side back;
    if (againstWall(rng_.uniform(0.8, 1.4), 0.35, r, back))
      b_.shelf(r.x0, r.y0, r.x1, r.y1, rng_.uniform(1.2, 2.0), rng_.uniform(0.3, 0.5), back);
  }
  void bed() {
    Rect r;
    WorldBuilder::Side back;
    const double w = rng_.chance(0.5) ? 1.4 : 0.9;
    if (againstWall(w, 2.0, r, back)) b_.bed(r.x0, r.y0, r.x1, r.y1, back);
  }
  void desk() {
    Rect r;
    WorldBuilder::Side back;
    const double w = rng_.uniform(1.2, 1.6), d = 0.7;
    if (!againstWall(w, d + 0.35, r, back)) return;  // with room for the chair pushed under it
    // The desk against the wall, its drawers at one end, the chair half under its top.
    using S = WorldBuilder::Side;
    const bool drawers_high = rng_.chance(0.5);
    switch (back) {
      case S::North:
        b_.desk(r.x0, r.y1 - d, r.x1, r.y1, drawers_high ? S::East : S::West);
        b_.chair(0.5 * (r.x0 + r.x1), r.y1 - d + 0.05, -M_PI / 2);
        break;
      case S::South:
        b_.desk(r.x0, r.y0, r.x1, r.y0 + d, drawers_high ? S::East : S::West);
        b_.chair(0.5 * (r.x0 + r.x1), r.y0 + d - 0.05, M_PI / 2);
        break;
      case S::East:
        b_.desk(r.x1 - d, r.y0, r.x1, r.y1, drawers_high ? S::North : S::South);
        b_.chair(r.x1 - d + 0.05, 0.5 * (r.y0 + r.y1), M_PI);
        break;
      case S::West:
        b_.desk(r.x0, r.y0, r.x0 + d, r.y1, drawers_high ? S::North : S::South);
        b_.chair(r.x0 + d - 0.05, 0.5 * (r.y0 + r.y1), 0.0);
        break;
    }
  }
  void diningTable() {
    Rect r;
    const double w = rng_.uniform(1.2, 1.8), d = 0.8;
    if (!anywhere(w + 0.5, d + 0.5, 0.8, r)) return;  // chairs included
    const double cx = 0.5 * (r.x0 + r.x1), cy = 0.5 * (r.y0 + r.y1);
    const bool along_x = r.x1 - r.x0 > r.y1 - r.y0;
    const double tw = along_x ? w : d, td = along_x ? d : w;
    b_.table(cx, cy, tw, td);
    // Chairs pushed under the top on the two long sides.
    for (const double s : {-1.0, 1.0}) {
      if (along_x)
        b_.chair(cx + s * 0.3, cy + s * (td / 2 - 0.1), s > 0 ? M_PI / 2 : -M_PI / 2);
      else
        b_.chair(cx + s * (tw / 2 - 0.1), cy + s * 0.3, s > 0 ? 0.0 : M_PI);
    }
  }
  void coffeeTable() {
    Rect r;
    if (anywhere(0.9, 0.55, 0.7, r)) b_.coffeeTable(0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1), r.x1 - r.x0, r.y1 - r.y0);
  }
  void floorLamp() {
    Rect r;
    WorldBuilder::Side back;
    if (againstWall(0.4, 0.4, r, back)) b_.floorLamp(0.5 * (r.x0 + r.x1), 0.5 * (r.y0 + r.y1));
  }
  void clutter() {
    Rect r;
    WorldBuilder::Side back;
    if (againstWall(rng_.uniform(0.4, 1.0), rng_.uniform(0.1, 0.3), r, back))
      b_.clutter(r.x0, r.y0, r.x1, r.y1, rng_.uniform(0.04, 0.08));
  }
  void cabinet() {
    Rect r;
    WorldBuilder::Side back;
    if (againstWall(rng_.uniform(0.6, 1.2), 0.5, r, back)) b_.cabinet(r.x0, r.y0, r.x1, r.y1, rng_.uniform(0.8, 2.0));
  }

 private:
  bool free(const Rect& r) const {
    for (const Rect& t : taken_)
      if (r.overlaps(t, kGap)) return false;
    return true;
  }
  static constexpr double kGap = 0.65;  ///< between pieces: the 0.52 m robot passes
  WorldBuilder& b_;
  Rng& rng_;
  Rect room_;
  std::vector<Rect> taken_;
};

/// Keeps a door's approach on both sides free of furniture.
Rect doorApproach(bool wall_along_x, double at, double a, double b) {
  return wall_along_x ? Rect{a - 0.3, at - 1.2, b + 0.3, at + 1.2} : Rect{at - 1.2, a - 0.3, at + 1.2, b + 0.3};
}

WorldSpec officeLarge() {
  // A 50 x 40 m office floor. Two corridors (2 m) run east-west at y 12-14 and 26-28; three
  // north-south corridors at x 0-2, 24-26 and 48-50 join them (two loops). Between the
  // corridors: 16 offices back to back, each with a door to its corridor. South of the first
  // corridor: an open-plan area (x 0-24) with desk clusters, open to the corridor through three
  // wide openings, and four labs (x 26-50). North of the second: ten rooms, two of them
  // passages to a hall along the north side (a third loop).
  WorldBuilder b(2.7);
  const double t = WorldBuilder::kWallThickness / 2;
  b.floorAndCeiling(-t - 0.3, -t - 0.3, 50 + t + 0.3, 40 + t + 0.3);
  b.wallX(-t, -2 * t, 50 + 2 * t);
  b.wallX(40 + t, -2 * t, 50 + 2 * t);
  b.wallY(-t, -2 * t, 40 + 2 * t);
  b.wallY(50 + t, -2 * t, 40 + 2 * t);
  // Corridor walls. South wall of corridor 1: the open-plan's openings and the labs' doors.
  b.wallX(12, 0, 50, {{4.0, 6.0}, {11.0, 13.0}, {18.0, 20.0}, {28.0, 29.0}, {34.5, 35.5}, {40.0, 41.0}, {46.0, 47.0}});
  b.wallY(25, 0, 12 - t);  // open plan | labs
  for (const double x : {31.25, 37.5, 43.75}) b.wallY(x, 0, 12 - t);
  // The middle block: offices x 2-24 and 26-48, y 14-20 (doors south) and 20-26 (doors north).
  std::vector<std::pair<double, double>> north1, south2;
  for (const double x0 : {2.0, 26.0}) {
    for (int i = 0; i < 4; ++i) {
      const double a = x0 + 5.5 * i;
      north1.push_back({a + 2.0, a + 3.0});
      south2.push_back({a + 2.5, a + 3.5});
      if (i > 0) b.wallY(a, 14 + t, 26 - t);
    }
  }
  b.wallX(14, 2 - t, 24 + t, {north1.begin(), north1.begin() + 4});
  b.wallX(14, 26 - t, 48 + t, {north1.begin() + 4, north1.end()});
  b.wallX(26, 2 - t, 24 + t, {south2.begin(), south2.begin() + 4});
  b.wallX(26, 26 - t, 48 + t, {south2.begin() + 4, south2.end()});
  b.wallX(20, 2 + t, 24 - t);
  b.wallX(20, 26 + t, 48 - t);
  b.wallY(2, 14 - t, 26 + t);
  b.wallY(24, 14 - t, 26 + t);
  b.wallY(26, 14 - t, 26 + t);
  b.wallY(48, 14 - t, 26 + t);
  // North of corridor 2: ten rooms 5 x 6 m (y 28-34), rooms 2 and 7 with a second door to the hall.
  std::vector<std::pair<double, double>> south_doors, hall_doors;
  for (int i = 0; i < 10; ++i) {
    const double a = 5.0 * i;
    south_doors.push_back({a + 2.0, a + 3.0});
    if (i == 2 || i == 7) hall_doors.push_back({a + 2.0, a + 3.0});
    if (i > 0) b.wallY(a, 28 + t, 34 - t);
  }
  b.wallX(28, 0, 50, south_doors);
  b.wallX(34, 0, 50, hall_doors);
  Rng rng(50040);
  // Furniture: offices get a desk, a shelf and a cabinet or clutter; labs tables; the open plan
  // desk clusters; the hall rows of tables; north rooms a desk or a sofa.
  const auto furnish = [&](const Rect& room, std::vector<Rect> keep, int kind) {
    RoomFurnisher f(b, rng, room, std::move(keep));
    if (kind == 0) {
      f.desk();
      f.shelf();
      if (rng.chance(0.5))
        f.cabinet();
      else
        f.clutter();
    } else if (kind == 1) {
      f.diningTable();
      f.diningTable();
      f.shelf();
      f.cabinet();
    } else {
      if (rng.chance(0.5))
        f.desk();
      else
        f.sofa(1.8);
      f.shelf();
      f.floorLamp();
    }
  };
  for (int i = 0; i < 8; ++i) {
    const double a = (i < 4 ? 2.0 : 26.0) + 5.5 * (i % 4);
    const std::pair<double, double> dn = north1[i], ds = south2[i];
    furnish({a + t, 14 + t, a + 5.5 - t, 20 - t}, {doorApproach(true, 14, dn.first, dn.second)}, 0);
    furnish({a + t, 20 + t, a + 5.5 - t, 26 - t}, {doorApproach(true, 26, ds.first, ds.second)}, 0);
  }
  const double lab_x[5] = {25.0, 31.25, 37.5, 43.75, 50.0};
  const double lab_door[4] = {28.0, 34.5, 40.0, 46.0};
  for (int i = 0; i < 4; ++i)
    furnish({lab_x[i] + t, t, lab_x[i + 1] - t, 12 - t}, {doorApproach(true, 12, lab_door[i], lab_door[i] + 1.0)}, 1);
  for (int i = 0; i < 10; ++i) {
    std::vector<Rect> keep = {doorApproach(true, 28, 5.0 * i + 2.0, 5.0 * i + 3.0)};
    if (i == 2 || i == 7) keep.push_back(doorApproach(true, 34, 5.0 * i + 2.0, 5.0 * i + 3.0));
    furnish({5.0 * i + t, 28 + t, 5.0 * (i + 1) - t, 34 - t}, keep, 2);
  }
  // The open plan: clusters of four desks around a shared shelf, clear of the openings.
  for (const double cx : {5.0, 12.0, 19.0})
    for (const double cy : {3.0, 7.5}) {
      b.desk(cx - 1.6, cy - 0.75, cx, cy, WorldBuilder::Side::West);
      b.desk(cx, cy - 0.75, cx + 1.6, cy, WorldBuilder::Side::East);
      b.desk(cx - 1.6, cy, cx, cy + 0.75, WorldBuilder::Side::West);
      b.desk(cx, cy, cx + 1.6, cy + 0.75, WorldBuilder::Side::East);
      b.chair(cx - 0.8, cy - 0.85, -M_PI / 2);
      b.chair(cx + 0.8, cy + 0.85, M_PI / 2);
    }
  b.shelf(0.05, 9.0, 0.4, 11.0, 1.6, 0.4, WorldBuilder::Side::West);
  // The hall: three rows of tables with chairs.
  for (int i = 0; i < 6; ++i)
    for (const double cy : {36.0, 38.5}) {
      const double cx = 5.0 + 8.0 * i;
      b.table(cx, cy, 1.8, 0.8);
      b.chair(cx - 0.4, cy - 0.5, -M_PI / 2);
      b.chair(cx + 0.4, cy + 0.5, M_PI / 2);
    }
  return {"office_large",
          "50 x 40 m office floor: two long corridors joined by three cross corridors (two loops), 16 offices "
          "between them, an open-plan area and four labs to the south, ten rooms and a hall to the north (two "
          "passages: a third loop), furniture throughout",
          {50.0, 40.0},
          Pose2D(1.0, 20.0, M_PI / 2),
          b.mesh(),
          ""};
}

}  // namespace

WorldSpec furnishedWorld(unsigned seed) {
  Rng rng(seed);
  WorldBuilder b(2.5);
  const double t = WorldBuilder::kWallThickness / 2;
  const int cols = rng.integer(2, 3), rows = 2;
  std::vector<double> xs = {0.0}, ys = {0.0};
  for (int c = 0; c < cols; ++c) xs.push_back(xs.back() + rng.uniform(3.6, 5.5));
  for (int r = 0; r < rows; ++r) ys.push_back(ys.back() + rng.uniform(3.6, 5.0));
  const double X = xs.back(), Y = ys.back();
  b.floorAndCeiling(-t - 0.3, -t - 0.3, X + t + 0.3, Y + t + 0.3);
  b.wallX(-t, -2 * t, X + 2 * t);
  b.wallX(Y + t, -2 * t, X + 2 * t);
  b.wallY(-t, -2 * t, Y + 2 * t);
  b.wallY(X + t, -2 * t, Y + 2 * t);
  // Doors: between every two rooms of a row, and between the rows in each column with a chance
  // (at least one: the flat is connected).
  std::vector<std::vector<Rect>> keep(cols * rows);
  const auto room = [&](int c, int r) { return r * cols + c; };
  const auto door = [&](double lo, double hi) {
    const double w = rng.uniform(0.9, 1.1);
    const double a = rng.uniform(lo + 0.35, hi - 0.35 - w);
    return std::make_pair(a, a + w);
  };
  for (int c = 1; c < cols; ++c)  // walls x = xs[c]
    for (int r = 0; r < rows; ++r) {
      const auto d = door(ys[r], ys[r + 1]);
      b.wallY(xs[c], ys[r] + (r > 0 ? t : 0.0), ys[r + 1] - (r + 1 < rows ? t : 0.0), {d});
      keep[room(c - 1, r)].push_back(doorApproach(false, xs[c], d.first, d.second));
      keep[room(c, r)].push_back(doorApproach(false, xs[c], d.first, d.second));
    }
  const int forced = rng.integer(0, cols - 1);
  std::vector<std::pair<double, double>> row_doors;
  for (int c = 0; c < cols; ++c) {
    if (c != forced && !rng.chance(0.6)) continue;
    const auto d = door(xs[c], xs[c + 1]);
    row_doors.push_back(d);
    keep[room(c, 0)].push_back(doorApproach(true, ys[1], d.first, d.second));
    keep[room(c, 1)].push_back(doorApproach(true, ys[1], d.first, d.second));
  }
  b.wallX(ys[1], 0.0, X, row_doors);
  // The start: the middle of the first room, kept free.
  const Pose2D start(0.5 * (xs[0] + xs[1]), 0.5 * (ys[0] + ys[1]), 0.0);
  keep[0].push_back({start.x - 0.8, start.y - 0.8, start.x + 0.8, start.y + 0.8});
  // Room kinds, shuffled.
  std::vector<int> kinds = {0, 1, 2, 3, 1, 2};
  for (size_t i = kinds.size() - 1; i > 0; --i) std::swap(kinds[i], kinds[rng.integer(0, static_cast<int>(i))]);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const Rect inside{xs[c] + t, ys[r] + t, xs[c + 1] - t, ys[r + 1] - t};
      RoomFurnisher f(b, rng, inside, keep[room(c, r)]);
      switch (kinds[room(c, r) % kinds.size()]) {
        case 0:  // living room
          f.sofa(rng.uniform(1.6, 2.2));
          f.sofa(0.9);  // an armchair
          f.coffeeTable();
          f.floorLamp();
          f.shelf();
          break;
        case 1:  // bedroom
          f.bed();
          f.shelf();
          f.clutter();
          f.floorLamp();
          break;
        case 2:  // study
          f.desk();
          f.shelf();
          f.cabinet();
          f.clutter();
          break;
        default:  // kitchen / dining
          f.diningTable();
          f.cabinet();
          f.cabinet();
          f.clutter();
          break;
      }
      // What every room gathers besides: another shelf, low clutter, a lamp (where they fit).
      f.shelf();
      f.clutter();
      f.floorLamp();
    }
  return {"furnished_" + std::to_string(seed),
          "furnished flat (seed " + std::to_string(seed) + "): " + std::to_string(cols * rows) + " rooms, " +
              std::to_string(static_cast<int>(std::lround(X))) + " x " +
              std::to_string(static_cast<int>(std::lround(Y))) +
              " m, sofas, beds, desks, shelves, tables, lamps, clutter",
          {X, Y},
          start,
          b.mesh(),
          ""};
}

namespace {

WorldSpec artifactsRoom() {
  // Thesis chapter 8 (figs. 8.7, 8.8): a 6 x 5 m room, a door (0.9 m) in the south wall to a 1.5 m
  // corridor, a table whose leg nearest the start carries a reflector (reads 10 cm short) and an
  // LCD monitor on the table that returns nothing. The robot must see the table by its legs and
  // must not take the leg for a pillar nor the door for a wall.
  WorldBuilder b(2.5);
  const double t = WorldBuilder::kWallThickness / 2;
  b.floorAndCeiling(-t - 0.5, -1.5 - t - 0.5, 6 + t + 0.5, 5 + t + 0.5);
  b.wallX(5 + t, -2 * t, 6 + 2 * t);              // north
  b.wallX(-t, -2 * t, 6 + 2 * t, {{2.5, 3.4}});   // south, with the door
  b.wallY(-t, -1.5 - 2 * t, 5 + 2 * t);           // west (room and corridor)
  b.wallY(6 + t, -1.5 - 2 * t, 5 + 2 * t);        // east
  b.wallX(-1.5 - t, -2 * t, 6 + 2 * t);           // corridor's south wall
  b.table(4.0, 3.0, 1.2, 0.7);                    // legs at x 3.45 / 4.55, y 2.70 / 3.30
  b.box({3.75, 3.08, 0.72}, {4.25, 3.13, 1.07});  // the monitor, standing on the table
  b.chair(4.0, 2.3, -M_PI / 2);
  b.cabinet(0.05, 4.0, 0.55, 4.95, 1.2);
  const std::string materials =
      "# artifacts_room: the scanner artifacts of thesis chapter 8 (generated by make_worlds).\n"
      "regions:\n"
      "  - name: table_leg_reflector   # the table's south-west leg (fig. 8.7)\n"
      "    material: retroreflective\n"
      "    min: [3.40, 2.65, 0.00]\n"
      "    max: [3.50, 2.75, 0.68]\n"
      "    bias_m: 0.10\n"
      "  - name: lcd_monitor           # on the table (fig. 8.8)\n"
      "    material: absorbing\n"
      "    min: [3.70, 3.05, 0.73]\n"
      "    max: [4.30, 3.15, 1.10]\n";
  return {"artifacts_room",
          "thesis chapter 8 artifacts: 6 x 5 m room, door to a corridor, a table with a retroreflective "
          "leg and an absorbing monitor on it, a chair, a cabinet",
          {6.1, 6.6},
          Pose2D(1.5, 2.0, 0.0),
          b.mesh(),
          materials};
}

}  // namespace

std::vector<WorldSpec> buildWorlds() {
  return {room10x8(),        officeLoop(),      corridor(),        officeLarge(),
          furnishedWorld(1), furnishedWorld(2), furnishedWorld(3), artifactsRoom()};
}

Pose2D defaultStartPose(const std::string& world_name) {
  for (const WorldSpec& w : buildWorlds())
    if (w.name == world_name) return w.start;
  // The real house from ../shared/data/worlds: its living room.
  if (world_name == "turtlebot3_house") return Pose2D(-3.0, 1.0, 0.0);
  // Any furnished_<seed>, not only the committed ones.
  if (world_name.rfind("furnished_", 0) == 0 && world_name.size() > 10 &&
      world_name.find_first_not_of("0123456789", 10) == std::string::npos && world_name.size() <= 19)
    return furnishedWorld(static_cast<unsigned>(std::stoul(world_name.substr(10)))).start;
  throw ConfigError(
      "no documented start pose for world '" + world_name +
      "' (known: room_10x8, office_loop, corridor, office_large, furnished_<seed>, artifacts_room, turtlebot3_house); "
      "give start_pose");
}

}  // namespace sim
}  // namespace scanstop
