#pragma once
/// The outlier filter of thesis 3.4 for organized 3D scans (rows = planes, columns = beams).
///
/// For every three neighbouring readings on a line of the angular scan mesh (along a plane, across
/// planes, and both diagonals) with ranges a, c, b (c in the middle), the triple agrees when
/// |(a + b) / 2 - c| < 0.01 m + 0.015 c: all three lie on a locally flat surface and are accepted.
/// A reading on no agreeing line is an outlier and becomes NaN. O(n).

#include <cstddef>

#include "scanstop_common/cloud.h"

namespace scanstop {

struct OutlierFilterConfig {
  double tolerance_abs_m = 0.01;  ///< the constant part of the tolerance [m]
  double tolerance_rel = 0.015;   ///< the part proportional to the middle range
};

/// Filters an organized cloud with ranges in place (points and ranges of outliers become NaN).
/// Returns the number of readings removed. Throws std::invalid_argument when the cloud is not
/// organized or has no ranges.
size_t filterOutliers(PointCloud& scan, const OutlierFilterConfig& config = OutlierFilterConfig());

}  // namespace scanstop
