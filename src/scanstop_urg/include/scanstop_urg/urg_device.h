#pragma once
/// The URG-04LX as a SCIP 2.0 client over a byte stream: the power-up handshake (SCIP 1.1 ->
/// SCIP2.0, stale streams, time-stamp mode), VV/PP/II, BM/QT/RS and GD single scans, with every
/// line's sum checked, tagged commands, timeouts and resynchronisation.

#include <cstdint>
#include <map>
#include <string>

#include "scanstop_urg/scip.h"
#include "scanstop_urg/serial.h"

namespace scanstop {
namespace urg {

struct UrgConfig {
  double reply_timeout_s = 1.0;  ///< for every reply but GD [s]
  double scan_timeout_s = 1.0;   ///< for a GD reply (one scan takes 100 ms at 600 rpm) [s]
  int first_step = 44;           ///< first GD step (>= AMIN)
  int last_step = 725;           ///< last GD step (<= AMAX)
  void validate() const;
};

/// What VV, PP and II said (PP values parsed; the others kept as text).
struct DeviceInfo {
  std::map<std::string, std::string> version, parameters, state;  ///< VV, PP, II fields
  int dmin_mm = 20, dmax_mm = 5600, ares = 1024, amin = 44, amax = 725, afrt = 384, scan_rpm = 600;
  std::string summary() const;
};

/// Link error counters (cumulative over the device's life).
struct LinkStats {
  uint64_t commands = 0;
  uint64_t checksum_errors = 0;
  uint64_t format_errors = 0;
  uint64_t timeouts = 0;
  uint64_t skipped_lines = 0;    ///< lines before the expected echo (stale replies, garbage)
  uint64_t scip11_switches = 0;  ///< times the device had to be switched from SCIP 1.1
};

class UrgDevice {
 public:
  UrgDevice(ByteStream& stream, const UrgConfig& config);
  /// Brings the sensor from any state (just powered up in SCIP 1.1, a stale stream from a crashed
  /// client, time-stamp mode) into SCIP 2.0 with the laser on; reads VV, PP and II and checks the
  /// configured steps against PP. Throws ScipError naming what failed.
  void initialize();
  /// One GD scan of first_step..last_step. Throws ScipError; kScip11 means: initialize again.
  ScanData scan();
  /// Laser off (QT).
  void laserOff();
  /// Sends `command` with a fresh tag and returns the complete reply (any status). Throws
  /// ScipError on a timeout, a bad sum, a malformed reply (after resynchronising) or kScip11.
  Reply command(const std::string& command, double timeout_s, bool kv_lines = false);
  const DeviceInfo& info() const { return info_; }
  const LinkStats& stats() const { return stats_; }
  const UrgConfig& config() const { return config_; }

 private:
  /// Sends a command and requires status 00 (or one of `also_ok`).
  Reply expectOk(const std::string& command, double timeout_s, bool kv_lines = false, const std::string& also_ok = "");
  void switchToScip2();

  LineChannel channel_;
  UrgConfig config_;
  DeviceInfo info_;
  LinkStats stats_;
  unsigned tag_ = 0;
};

}  // namespace urg
}  // namespace scanstop
