#include "scanstop_common/scan_filter.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace scanstop {

size_t filterOutliers(PointCloud& scan, const OutlierFilterConfig& config) {
  if (!scan.hasRanges() || scan.ranges.size() != scan.size())
    throw std::invalid_argument("the outlier filter needs a range per point");
  const std::string problem = scan.layoutProblem();
  if (!problem.empty()) throw std::invalid_argument("the outlier filter needs an organized scan: " + problem);
  const int rows = static_cast<int>(scan.height), cols = static_cast<int>(scan.width);
  const std::vector<float>& r = scan.ranges;
  std::vector<uint8_t> accepted(r.size(), 0);
  // Line directions in the (plane, beam) mesh: along the plane, across planes, both diagonals.
  const int dirs[4][2] = {{0, 1}, {1, 0}, {1, 1}, {1, -1}};
  for (int p = 0; p < rows; ++p) {
    for (int b = 0; b < cols; ++b) {
      const size_t ic = static_cast<size_t>(p) * cols + b;
      const float c = r[ic];
      if (!std::isfinite(c)) continue;
      const double tolerance = config.tolerance_abs_m + config.tolerance_rel * c;
      for (const auto& d : dirs) {
        const int p0 = p - d[0], b0 = b - d[1], p1 = p + d[0], b1 = b + d[1];
        if (p0 < 0 || p1 >= rows || b0 < 0 || b0 >= cols || b1 < 0 || b1 >= cols) continue;
        const size_t i0 = static_cast<size_t>(p0) * cols + b0, i1 = static_cast<size_t>(p1) * cols + b1;
        const float a = r[i0], e = r[i1];
        if (!std::isfinite(a) || !std::isfinite(e)) continue;
        if (std::abs(0.5 * (a + e) - c) < tolerance) {
          accepted[ic] = accepted[i0] = accepted[i1] = 1;
        }
      }
    }
  }
  size_t removed = 0;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t i = 0; i < r.size(); ++i) {
    if (std::isfinite(scan.ranges[i]) && !accepted[i]) {
      scan.ranges[i] = nan;
      scan.points[i] = Eigen::Vector3f::Constant(nan);
      if (scan.hasNormals()) scan.normals[i] = Eigen::Vector3f::Constant(nan);
      ++removed;
    }
  }
  return removed;
}

}  // namespace scanstop
