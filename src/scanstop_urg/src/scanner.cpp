#include "scanstop_urg/scanner.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace urg {

Eigen::Vector3f ScanGeometry::direction(int plane, int planes, int beam) const {
  const double phi = M_PI * plane / planes;
  const double theta = (first_step + beam - front_step) * 2.0 * M_PI / steps_per_turn;
  const double h = std::sin(theta);
  return Eigen::Vector3f(static_cast<float>(h * std::cos(phi)), static_cast<float>(h * std::sin(phi)),
                         static_cast<float>(std::cos(theta)));
}

Eigen::Vector3f ScanGeometry::origin(int plane, int planes) const {
  const double phi = M_PI * plane / planes;
  return Eigen::Vector3f(static_cast<float>(x_offset_m + mount_offset_m * std::cos(phi)),
                         static_cast<float>(mount_offset_m * std::sin(phi)), static_cast<float>(height_m));
}

void ScanGeometry::validate() const {
  requireInRange("scanner/height_m", height_m, 0.05, 3.0, "m");
  requireInRange("scanner/x_offset_m", x_offset_m, -1.0, 1.0, "m");
  requireInRange("scanner/mount_offset_m", mount_offset_m, -0.5, 0.5, "m");
  requireInRange("scanner/min_range_m", min_range_m, 0.02, 1.0, "m");
  requireInRange("scanner/max_range_m", max_range_m, min_range_m + 0.01, 100.0, "m");
  if (steps_per_turn < 4 || steps_per_turn > 65536)
    throw ConfigError("scanner/steps_per_turn = " + std::to_string(steps_per_turn) + " must be in 4..65536");
  if (first_step < 0 || last_step <= first_step || last_step >= steps_per_turn)
    throw ConfigError("scanner/first_step = " + std::to_string(first_step) + ", scanner/last_step = " +
                      std::to_string(last_step) + ": need 0 <= first_step < last_step < steps_per_turn");
  if (front_step < 0 || front_step >= steps_per_turn)
    throw ConfigError("scanner/front_step = " + std::to_string(front_step) + " must be in 0..steps_per_turn-1");
}

float rangeFromValue(uint32_t value_mm, const ScanGeometry& geometry) {
  // Compare in whole millimetres (5600 * 0.001 > 5.6 in floating point).
  const long min_mm = std::lround(geometry.min_range_m * 1000.0), max_mm = std::lround(geometry.max_range_m * 1000.0);
  const long v = static_cast<long>(value_mm);
  if (v < 20 || v < min_mm || v > max_mm) return std::numeric_limits<float>::quiet_NaN();
  return static_cast<float>(v * 0.001);
}

PointCloud emptyScan(const ScanGeometry& geometry, int planes) {
  PointCloud cloud;
  cloud.width = static_cast<uint32_t>(geometry.beams());
  cloud.height = static_cast<uint32_t>(planes);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.points.assign(static_cast<size_t>(planes) * cloud.width, Eigen::Vector3f::Constant(nan));
  cloud.ranges.assign(cloud.points.size(), nan);
  return cloud;
}

size_t assemblePlane(PointCloud& cloud, const ScanGeometry& geometry, int plane, int planes,
                     const std::vector<uint32_t>& values) {
  const int beams = geometry.beams();
  if (static_cast<int>(values.size()) != beams)
    throw std::invalid_argument("plane " + std::to_string(plane) + " has " + std::to_string(values.size()) +
                                " values, expected " + std::to_string(beams));
  if (plane < 0 || plane >= planes || static_cast<int>(cloud.height) != planes ||
      static_cast<int>(cloud.width) != beams)
    throw std::invalid_argument("plane " + std::to_string(plane) + " does not fit the cloud layout");
  const Eigen::Vector3f o = geometry.origin(plane, planes);
  // The same expressions as direction(), with the plane's trigonometry hoisted out of the loop.
  const double phi = M_PI * plane / planes, cos_phi = std::cos(phi), sin_phi = std::sin(phi);
  size_t valid = 0;
  for (int b = 0; b < beams; ++b) {
    const float r = rangeFromValue(values[static_cast<size_t>(b)], geometry);
    const size_t i = static_cast<size_t>(plane) * beams + b;
    if (!std::isfinite(r)) continue;
    const double theta = (geometry.first_step + b - geometry.front_step) * 2.0 * M_PI / geometry.steps_per_turn;
    const double h = std::sin(theta);
    const Eigen::Vector3f d(static_cast<float>(h * cos_phi), static_cast<float>(h * sin_phi),
                            static_cast<float>(std::cos(theta)));
    cloud.ranges[i] = r;
    cloud.points[i] = o + r * d;
    ++valid;
  }
  return valid;
}

void ScannerConfig::validate() const {
  geometry.validate();
  if (max_plane_retries < 0 || max_plane_retries > 20)
    throw ConfigError("max_plane_retries = " + std::to_string(max_plane_retries) + " must be in 0..20");
  if (max_consecutive_dropped < 1)
    throw ConfigError("max_consecutive_dropped = " + std::to_string(max_consecutive_dropped) + " must be >= 1");
  requireInRange("settle_time_s", settle_time_s, 0.0, 5.0, "s");
  requireInRange("outlier_tolerance_abs_m", filter.tolerance_abs_m, 0.0, 1.0, "m");
  requireInRange("outlier_tolerance_rel", filter.tolerance_rel, 0.0, 1.0);
}

RotatingScanner::RotatingScanner(UrgDevice& urg, RotationPlatform& platform, const ScannerConfig& config)
    : urg_(urg), platform_(platform), config_(config) {
  config_.validate();
}

bool RotatingScanner::readPlane(std::vector<uint32_t>* values, ScanResult* result, std::string* last_error) {
  for (int attempt = 0; attempt <= config_.max_plane_retries; ++attempt) {
    if (attempt > 0) ++result->plane_retries;
    try {
      ScanData d = urg_.scan();
      *values = std::move(d.values);
      return true;
    } catch (const ScipError& e) {
      *last_error = e.what();
      if (e.kind() == ScipError::Kind::kDisconnected) throw;
      if (e.kind() == ScipError::Kind::kScip11) urg_.initialize();  // power-cycled: handshake again, re-read
    }
  }
  return false;
}

ScanResult RotatingScanner::takeScan(int planes, const std::function<void(int, int)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  ScanResult result;
  auto finish = [&](bool success, const std::string& message) {
    result.success = success;
    result.message = message;
    result.duration_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  };
  if (planes < 1 || planes > stepper::kMaxCount)
    return finish(false, "planes = " + std::to_string(planes) + " is outside 1.." + std::to_string(stepper::kMaxCount));
  const ScanGeometry& g = config_.geometry;
  result.cloud = emptyScan(g, planes);
  result.raw_points = static_cast<uint32_t>(planes * g.beams());
  try {
    platform_.prepare(planes);
  } catch (const PlatformError& e) {
    result.device_lost = e.linkLost();
    return finish(false, std::string("rotation platform: ") + e.what());
  }
  int consecutive_dropped = 0;
  std::vector<uint32_t> values;
  std::string last_error;
  try {
    for (int p = 0; p < planes; ++p) {
      if (p > 0) {
        const int position = platform_.advance();
        if (position != p)
          return finish(false, "rotation platform reports position " + std::to_string(position) + " after step " +
                                   std::to_string(p) + " (expected " + std::to_string(p) + ")");
      }
      if (config_.settle_time_s > 0) std::this_thread::sleep_for(std::chrono::duration<double>(config_.settle_time_s));
      if (readPlane(&values, &result, &last_error)) {
        for (uint32_t v : values) result.error_codes += v < 20 ? 1 : 0;
        assemblePlane(result.cloud, g, p, planes, values);
        consecutive_dropped = 0;
      } else {
        ++result.planes_dropped;
        if (++consecutive_dropped >= config_.max_consecutive_dropped) {
          result.device_lost = true;
          return finish(false, "the URG stopped answering: " + std::to_string(consecutive_dropped) +
                                   " planes in a row lost after " + std::to_string(config_.max_plane_retries) +
                                   " re-reads each (last error: " + last_error + ")");
        }
      }
      if (progress) progress(p + 1, planes);
    }
  } catch (const PlatformError& e) {
    result.device_lost = e.linkLost();
    return finish(false, std::string("rotation platform: ") + e.what());
  } catch (const ScipError& e) {
    result.device_lost = true;
    return finish(false, std::string("URG: ") + e.what());
  }
  std::string note;
  try {
    platform_.park();
  } catch (const PlatformError& e) {
    note = std::string("; parking the platform failed: ") + e.what();
  }
  if (config_.outlier_filter)
    result.outliers_removed = static_cast<uint32_t>(filterOutliers(result.cloud, config_.filter));
  result.valid_points = static_cast<uint32_t>(result.cloud.countFinite());
  return finish(true, std::to_string(result.valid_points) + " valid points, " + std::to_string(result.planes_dropped) +
                          " planes dropped, " + std::to_string(result.plane_retries) + " re-reads, " +
                          std::to_string(result.outliers_removed) + " outliers removed" + note);
}

}  // namespace urg
}  // namespace scanstop
