// The fused map kept up to date during a mission (issue #20): a scan taken back leaves the field as
// it was without it; the tracker integrates new scans, takes back and integrates again the scans SLAM
// moved (not those within the tolerance), names scans it cannot read, and its map meshes like the
// pass over the whole directory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/fused_map.h"
#include "scanstop_mesher/fused_tracker.h"
#include "synthetic_room.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

/// Scan i of a map directory in the map frame, with its sensor origin there.
std::pair<std::vector<Eigen::Vector3f>, Eigen::Vector3f> scanInMap(const MapDirectory& map, size_t i) {
  const PointCloud cloud = map.loadScanInMap(i);
  const MapScanInfo& info = map.scans()[i];
  return {cloud.points, info.map_pose.toIsometry3f() * info.sensor_origin.cast<float>()};
}

/// Largest distance difference and number of weight differences over a 3 cm lattice of the room.
struct FieldDifference {
  float distance = 0.0f;
  size_t weights = 0, seen = 0, samples = 0;
};
FieldDifference compare(const FusedMap& a, const FusedMap& b) {
  FieldDifference d;
  const test::Box room = test::roomBounds();
  for (float x = room.lo.x() - 0.1f; x <= room.hi.x() + 0.1f; x += 0.03f)
    for (float y = room.lo.y() - 0.1f; y <= room.hi.y() + 0.1f; y += 0.03f)
      for (float z = room.lo.z() - 0.1f; z <= room.hi.z() + 0.1f; z += 0.03f) {
        const Eigen::Vector3f p(x, y, z);
        ++d.samples;
        d.seen += a.weightAt(p) > 0.0f;
        d.weights += a.weightAt(p) != b.weightAt(p);
        d.distance = std::max(d.distance, std::abs(a.distanceAt(p) - b.distanceAt(p)));
      }
  return d;
}

FusedMapConfig missionConfig() {  // bpa_mesher_node's: 0.2 m of carving and the far pass
  FusedMapConfig c;
  c.carve_m = 0.2;
  c.carve_far = true;
  c.threads = 1;
  return c;
}

}  // namespace

TEST(FusedMapTracker, AScanTakenBackLeavesTheFieldWithoutIt) {
  test_util::TempDir tmp("fused_tracker_test");
  test::writeRoomMap(tmp.path + "/map");
  const MapDirectory map(tmp.path + "/map");
  const auto a = scanInMap(map, 0), b = scanInMap(map, 1);
  FusedMap only_a(missionConfig()), both(missionConfig());
  only_a.integrate(a.first, a.second);
  both.integrate(a.first, a.second);
  both.integrate(b.first, b.second);
  EXPECT_GT(both.observedVoxels(), only_a.observedVoxels() + 10000) << "the second scan sees more";
  EXPECT_EQ(both.deintegrate(b.first, b.second), b.first.size());
  EXPECT_EQ(both.stats().scans, 1u);
  EXPECT_EQ(both.observedVoxels(), only_a.observedVoxels());
  const FieldDifference d = compare(only_a, both);
  EXPECT_GT(d.seen, d.samples / 20);
  EXPECT_EQ(d.weights, 0u);
  EXPECT_LT(d.distance, 1e-4f);
}

TEST(FusedMapTracker, FollowsNewScansAndMovedPoses) {
  test_util::TempDir tmp("fused_tracker_test");
  test::writeRoomMap(tmp.path + "/map");
  FusedMapTracker tracker(missionConfig());
  FusedTrackerUpdate u = tracker.update(tmp.path + "/map");
  EXPECT_EQ(u.integrated, 2u);
  EXPECT_EQ(u.reintegrated, 0u);
  EXPECT_EQ(u.scans, 2u);
  EXPECT_TRUE(u.problems.empty());
  u = tracker.update(tmp.path + "/map");
  EXPECT_EQ(u.integrated + u.reintegrated, 0u) << "nothing changed";

  MapDirectory map(tmp.path + "/map");
  Pose2D pose = map.scans()[1].map_pose;
  pose.x += 0.001;  // within repose_m (5 mm): kept where it is
  map.updatePoses({{1u, pose}});
  u = tracker.update(tmp.path + "/map");
  EXPECT_EQ(u.reintegrated, 0u);
  pose.x += 0.05;  // 5 cm and a degree: taken back and integrated again
  pose.yaw += M_PI / 180.0;
  map.updatePoses({{1u, pose}});
  u = tracker.update(tmp.path + "/map");
  EXPECT_EQ(u.reintegrated, 1u);
  EXPECT_EQ(u.integrated, 0u);
  EXPECT_EQ(tracker.scans(), 2u);

  // The same field as a map built afresh at the new poses (the near integration; the far carving
  // pass runs over all scans when the map is taken).
  // (Its two new scans on two threads, each into grids of its own, merged.)
  FusedMapConfig two_threads = missionConfig();
  two_threads.threads = 2;
  FusedMapTracker fresh(two_threads);
  EXPECT_EQ(fresh.update(tmp.path + "/map").integrated, 2u);
  const FieldDifference d = compare(fresh.map(), tracker.map());
  EXPECT_GT(d.seen, d.samples / 20);
  EXPECT_EQ(d.weights, 0u);
  EXPECT_LT(d.distance, 1e-4f);

  // Its snapshot (the far pass over all scans on a copy) meshes like the pass over the whole directory.
  FusedMap whole(missionConfig());
  integrateMapDirectory(whole, tmp.path + "/map");
  const TriangleMesh batch = whole.extractMesh(), live = tracker.snapshot().extractMesh();
  std::printf("pass over the directory: %zu triangles; tracker: %zu\n", batch.faces.size(), live.faces.size());
  EXPECT_NEAR(static_cast<double>(live.faces.size()), static_cast<double>(batch.faces.size()),
              0.001 * batch.faces.size());
  EXPECT_EQ(tracker.map().observedVoxels(), fresh.map().observedVoxels());
}

TEST(FusedMapTracker, NamesWhatItCannotReadAndKeepsTheRest) {
  test_util::TempDir tmp("fused_tracker_test");
  FusedMapTracker tracker(missionConfig());
  EXPECT_THROW(tracker.update(tmp.path + "/no_map"), IoError);
  test::writeRoomMap(tmp.path + "/map");
  std::remove((tmp.path + "/map/scans/scan_0001.pcd").c_str());
  const FusedTrackerUpdate u = tracker.update(tmp.path + "/map");
  EXPECT_EQ(u.integrated, 1u);
  ASSERT_FALSE(u.problems.empty());
  EXPECT_NE(u.problems.front().find("scan_0001.pcd"), std::string::npos) << u.problems.front();
  FusedTrackerConfig bad;
  bad.repose_m = -1.0;
  EXPECT_THROW(FusedMapTracker(missionConfig(), bad), ConfigError);
}
