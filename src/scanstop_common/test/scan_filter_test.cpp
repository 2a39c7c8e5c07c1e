#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "scanstop_common/scan_filter.h"

namespace scanstop {
namespace {

/// A scan of a flat wall: every reading agrees with its neighbours.
PointCloud flatScan(int rows, int cols, float range) {
  PointCloud c;
  c.width = cols;
  c.height = rows;
  for (int p = 0; p < rows; ++p)
    for (int b = 0; b < cols; ++b) {
      c.points.emplace_back(range, 0.01f * b, 0.01f * p);
      c.ranges.push_back(range);
    }
  return c;
}

TEST(OutlierFilter, KeepsSurfacesAndRemovesIsolatedSpikes) {
  PointCloud c = flatScan(10, 12, 2.0f);
  c.ranges[5 * 12 + 6] = 3.5f;  // a random reading in the middle of the wall
  const size_t removed = filterOutliers(c);
  EXPECT_EQ(removed, 1u);
  EXPECT_TRUE(std::isnan(c.ranges[5 * 12 + 6]));
  EXPECT_FALSE(c.points[5 * 12 + 6].allFinite());
  EXPECT_EQ(c.countFinite(), 119u);
}

TEST(OutlierFilter, ToleranceFollowsTheThesisFormula) {
  // Middle reading 2.0 m: tolerance 0.01 + 0.015 * 2.0 = 0.04 m.
  for (const auto& [delta, keep] : {std::pair<float, bool>{0.039f, true}, std::pair<float, bool>{0.041f, false}}) {
    PointCloud c;
    c.width = 3;
    c.height = 1;
    c.ranges = {2.0f - delta, 2.0f, 2.0f - delta};  // (a + b) / 2 - c = -delta
    c.points.assign(3, Eigen::Vector3f(1, 1, 1));
    const size_t removed = filterOutliers(c);
    EXPECT_EQ(removed, keep ? 0u : 3u) << "delta " << delta;
  }
}

TEST(OutlierFilter, AcceptsPointsOnDiagonalAndCrossPlaneLines) {
  // A single valid column across planes (only the across-planes line exists).
  PointCloud c = flatScan(5, 3, 1.0f);
  for (int p = 0; p < 5; ++p) {
    c.ranges[p * 3 + 0] = std::numeric_limits<float>::quiet_NaN();
    c.ranges[p * 3 + 2] = std::numeric_limits<float>::quiet_NaN();
  }
  EXPECT_EQ(filterOutliers(c), 0u);
  // A lone diagonal line of three.
  PointCloud d = flatScan(3, 3, 1.0f);
  for (int i = 0; i < 9; ++i)
    if (i != 0 && i != 4 && i != 8) d.ranges[i] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(filterOutliers(d), 0u);
  // Two isolated points with no complete line are removed.
  PointCloud e = flatScan(3, 3, 1.0f);
  for (int i = 0; i < 9; ++i)
    if (i != 0 && i != 4) e.ranges[i] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(filterOutliers(e), 2u);
}

TEST(OutlierFilter, RejectsCloudsWithoutRanges) {
  PointCloud c;
  c.push_back({1, 2, 3});
  EXPECT_THROW(filterOutliers(c), std::invalid_argument);
}

}  // namespace
}  // namespace scanstop
