#pragma once
/// The synthetic world of the surface tests: a 4 x 3 x 2.5 m room, interior [0, 4] x [0, 3], with a
/// 1 x 1 x 0.8 m box in it whose far side a scan from (1, 1.5) cannot see.

#include "scanstop_common/cloud.h"
#include "scanstop_sim/world_builder.h"

namespace scanstop {
namespace eval {
namespace test {

inline TriangleMesh roomWithBox() {
  constexpr double kT = sim::WorldBuilder::kWallThickness / 2;
  sim::WorldBuilder b(2.5);
  b.floorAndCeiling(-2 * kT, -2 * kT, 4 + 2 * kT, 3 + 2 * kT);
  b.wallX(-kT, -2 * kT, 4 + 2 * kT);
  b.wallX(3 + kT, -2 * kT, 4 + 2 * kT);
  b.wallY(-kT, -2 * kT, 3 + 2 * kT);
  b.wallY(4 + kT, -2 * kT, 3 + 2 * kT);
  b.box(Eigen::Vector3d(2.5, 1.0, 0.0), Eigen::Vector3d(3.5, 2.0, 0.8));
  return b.mesh();
}

}  // namespace test
}  // namespace eval
}  // namespace scanstop
