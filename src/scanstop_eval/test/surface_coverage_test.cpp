// Surface coverage of a map (issue #19 point 5): the visible surface of a room is held completely by
// its own elements, half by a scan of it and hardly at all by the same scan at a wrong pose.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "room_with_box.h"
#include "scanstop_common/cli_test.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_eval/surface_coverage.h"
#include "scanstop_sim/world_builder.h"

using namespace scanstop;
using namespace scanstop::eval;

namespace {

using test::roomWithBox;

struct Fixture {
  Fixture() : start(1.0, 1.5, 0.0), sim(sim::World::fromMesh(roomWithBox(), "room"), config(), start) {}
  static sim::SimConfig config() {
    sim::SimConfig sc;
    sc.errors = sim::makeProfile("perfect");
    return sc;
  }
  Pose2D start;
  sim::Simulator sim;
};

OracleConfig quick() {
  OracleConfig c;
  c.planes = 100;
  return c;
}

}  // namespace

TEST(SurfaceCoverage, TheVisibleSurfaceHoldsItselfAndNothingHoldsNothing) {
  Fixture f;
  const VisibleSurface v = visibleSurface(f.sim, f.start, quick());
  EXPECT_GT(v.candidates, 20u);
  EXPECT_EQ(v.candidates_refused, 0u);
  // The inner faces, the box and the ceiling are visible; the outer faces of the walls are not.
  EXPECT_GT(v.visible_count, v.elements.size() / 4);
  EXPECT_LT(v.visible_count, v.elements.size() * 3 / 4);
  std::vector<Eigen::Vector3f> all, hidden;
  for (size_t i = 0; i < v.elements.size(); ++i) (v.visible[i] ? all : hidden).push_back(v.elements.point(i));
  SurfaceCoverage held(v, 0.03);
  EXPECT_EQ(held.covered(), 0u);
  EXPECT_DOUBLE_EQ(held.share(), 0.0);
  held.add(hidden);  // the outer faces count for nothing
  EXPECT_EQ(held.covered(), 0u);
  held.add(all);
  EXPECT_EQ(held.covered(), v.visible_count);
  EXPECT_DOUBLE_EQ(held.share(), 1.0);
  EXPECT_EQ(held.points(), v.elements.size());
  EXPECT_THROW(SurfaceCoverage(v, 0.06), ConfigError);  // more than the 5 cm element
}

TEST(SurfaceCoverage, AMapHoldsWhatItsScansSawAtTheirPosesNotAtWrongOnes) {
  Fixture f;
  const VisibleSurface v = visibleSurface(f.sim, f.start, quick());
  // One perfect 400-plane scan at the start, stored as the first scan of a map (the map frame is the
  // start's; world_T_map = start).
  f.sim.reset(f.start, -1);
  const sim::ScanOutput scan = f.sim.scan(400);
  test_util::TempDir dir("surface_coverage_test");
  ASSERT_FALSE(dir.path.empty());
  {
    MapDirectory map(dir.path);
    MapScanInfo info;
    info.index = 0;
    info.map_pose = Pose2D(0.0, 0.0, 0.0);
    info.odom_pose = info.map_pose;
    map.append(info, scan.cloud);
  }
  const MapDirectory map(dir.path);
  std::vector<std::string> problems;
  const MapSurfaceCoverage right = mapSurfaceCoverage(v, map, f.start, 0.03, &problems);
  EXPECT_TRUE(problems.empty());
  EXPECT_EQ(right.scans, 1u);
  EXPECT_EQ(right.visible, v.visible_count);
  EXPECT_GT(right.points, 10000u);
  // The box hides its far side and a strip of floor-level wall behind it; the rest is in sight.
  EXPECT_GT(right.share, 0.8);  // 92 % when written
  EXPECT_LT(right.share, 0.99);
  // The same scan 10 cm off in x and y: only surfaces parallel to the offset (the ceiling, the box's
  // top) still lie within 3 cm.
  const MapSurfaceCoverage wrong = mapSurfaceCoverage(v, map, Pose2D(f.start.x + 0.1, f.start.y + 0.1, 0.0), 0.03);
  EXPECT_LT(wrong.share, 0.4)  // 25 % when written
      << "right " << right.share << ", wrong " << wrong.share;
}
