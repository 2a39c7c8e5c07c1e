#pragma once
/// Small worlds the scanstop_eval tests measure against (test code only).

#include "scanstop_common/cloud.h"
#include "scanstop_sim/world_builder.h"

namespace scanstop {
namespace test_util {

/// A square room 2.5 m high, interior [0, side_m]^2 (walls 0.1 m thick, their inner faces at 0 and
/// side_m), its floor and ceiling reaching floor_margin_m beyond the interior on every side.
inline TriangleMesh squareRoom(double side_m, double floor_margin_m) {
  sim::WorldBuilder b(2.5);
  b.floorAndCeiling(-floor_margin_m, -floor_margin_m, side_m + floor_margin_m, side_m + floor_margin_m);
  b.wallX(-0.05, -0.1, side_m + 0.1);
  b.wallX(side_m + 0.05, -0.1, side_m + 0.1);
  b.wallY(-0.05, -0.1, side_m + 0.1);
  b.wallY(side_m + 0.05, -0.1, side_m + 0.1);
  return b.mesh();
}

}  // namespace test_util
}  // namespace scanstop
