#pragma once
/// A full 3D scan with the rotating URG: one GD scan per platform step, assembled into the
/// organized cloud (rows = planes, columns = beams) in base_link with the geometry convention of
/// scanstop_sim's ScannerConfig; transmission errors re-read with bounded retries, then the plane
/// is dropped and counted; the thesis 3.4 outlier filter (scanstop_common/scan_filter.h).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>

#include "scanstop_common/cloud.h"
#include "scanstop_common/scan_filter.h"
#include "scanstop_urg/platform.h"
#include "scanstop_urg/urg_device.h"

namespace scanstop {
namespace urg {

/// Mount geometry. The scan plane is vertical and turns about the vertical axis through the
/// rotation centre; step s points at (s - front_step) * 2 pi / steps_per_turn from +z within the
/// plane; plane k of N is turned by k * pi / N about z from base_link's x axis.
struct ScanGeometry {
  double height_m = 0.45;       ///< rotation centre above the floor (base_link z) [m]
  double x_offset_m = 0.0;      ///< rotation axis ahead of base_link's origin [m]
  double mount_offset_m = 0.0;  ///< laser optical centre off the rotation axis, along the plane [m]
  int first_step = 44;          ///< first step scanned (AMIN)
  int last_step = 725;          ///< last step scanned (AMAX)
  int front_step = 384;         ///< AFRT: the step along the plane's "up" axis
  int steps_per_turn = 1024;    ///< ARES
  double min_range_m = 0.02;    ///< shorter readings (and the error codes below DMIN) are invalid [m]
  double max_range_m = 5.6;     ///< longer readings are invalid [m]

  int beams() const { return last_step - first_step + 1; }
  /// Unit direction of beam `beam` (0-based) of plane `plane` of `planes`, in base_link.
  Eigen::Vector3f direction(int plane, int planes, int beam) const;
  /// Origin of the beams of plane `plane` in base_link [m].
  Eigen::Vector3f origin(int plane, int planes) const;
  /// Throws ConfigError naming the bad field.
  void validate() const;
};

/// A raw URG value [mm] in metres: NaN for an error code (below DMIN) or outside min..max range.
float rangeFromValue(uint32_t value_mm, const ScanGeometry& geometry);

/// An organized all-NaN cloud of `planes` x beams with ranges.
PointCloud emptyScan(const ScanGeometry& geometry, int planes);
/// Writes one plane's values into the cloud (row `plane`); returns the number of valid points.
/// Throws std::invalid_argument when the value count does not match the beams.
size_t assemblePlane(PointCloud& cloud, const ScanGeometry& geometry, int plane, int planes,
                     const std::vector<uint32_t>& values);

struct ScannerConfig {
  ScanGeometry geometry;
  int max_plane_retries = 3;        ///< re-reads of a plane after a transmission error
  int max_consecutive_dropped = 3;  ///< abort the scan when this many planes in a row are lost
  double settle_time_s = 0.02;      ///< wait after a platform step before the GD [s]
  bool outlier_filter = true;       ///< apply the thesis 3.4 filter
  OutlierFilterConfig filter;
  void validate() const;
};

/// The outcome of one full scan.
struct ScanResult {
  bool success = false;
  std::string message;          ///< why it failed, or a summary
  PointCloud cloud;             ///< organized, base_link, NaN = invalid
  uint32_t raw_points = 0;      ///< planes x beams
  uint32_t valid_points = 0;    ///< finite points after all filtering
  uint32_t planes_dropped = 0;  ///< planes lost after the bounded re-reads
  uint32_t outliers_removed = 0;
  uint32_t plane_retries = 0;  ///< re-reads of planes
  uint32_t error_codes = 0;    ///< readings the URG reported as error codes (below DMIN)
  double duration_s = 0.0;     ///< wall time [s]
  bool device_lost = false;    ///< the link failed: reconnect before the next scan
};

/// Takes full scans with a URG and a rotation platform.
class RotatingScanner {
 public:
  RotatingScanner(UrgDevice& urg, RotationPlatform& platform, const ScannerConfig& config);
  /// Scans `planes` planes (1..4000); `progress(done, planes)` after every plane. Never throws
  /// for device trouble: the result says what went wrong.
  ScanResult takeScan(int planes, const std::function<void(int, int)>& progress = nullptr);

 private:
  /// One plane with bounded re-reads; false when it is dropped. Throws ScipError for a lost link.
  bool readPlane(std::vector<uint32_t>* values, ScanResult* result, std::string* last_error);

  UrgDevice& urg_;
  RotationPlatform& platform_;
  ScannerConfig config_;
};

}  // namespace urg
}  // namespace scanstop
