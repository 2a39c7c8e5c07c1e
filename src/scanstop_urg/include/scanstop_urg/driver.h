#pragma once
/// The rotating URG as one device with a connection life cycle: opens the URG's and the platform's
/// serial ports, performs the handshake, takes full scans, notices a lost device and reconnects
/// when asked. ROS-free; the byte streams come from a factory so that tests can use emulators.

#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "scanstop_urg/platform.h"
#include "scanstop_urg/scanner.h"
#include "scanstop_urg/serial.h"
#include "scanstop_urg/urg_device.h"

namespace scanstop {
namespace urg {

struct DriverConfig {
  std::string urg_port = "/dev/ttyACM0";       ///< URG serial device
  int urg_baud = 19200;                        ///< RS-232 rate (no effect on USB)
  std::string platform_port = "/dev/ttyUSB0";  ///< stepper controller serial device
  int platform_baud = 9600;
  UrgConfig urg;
  StepperConfig stepper;
  ScannerConfig scanner;
  /// Validates every part; throws ConfigError naming the parameter.
  void validate() const;
};

/// Opens a byte stream to a device; throws ScipError(kDisconnected) when it cannot.
using StreamFactory = std::function<std::unique_ptr<ByteStream>(const std::string& path, int baud)>;
/// The default factory: SerialPort.
StreamFactory serialStreamFactory();

/// Counters for diagnostics (cumulative since start).
struct DriverStats {
  bool connected = false;
  std::string state;  ///< "connected: <device>" or why not
  uint64_t connects = 0, connection_losses = 0;
  uint64_t scans_ok = 0, scans_failed = 0;
  uint64_t planes_dropped = 0, plane_retries = 0;
  uint64_t checksum_errors = 0, format_errors = 0, timeouts = 0, skipped_lines = 0, scip11_switches = 0;
  uint64_t outliers_removed = 0, points_before_filter = 0;
  double last_outlier_share = 0.0;  ///< outliers / valid points before the filter, last scan
  std::string last_error;
};

class UrgDriver {
 public:
  explicit UrgDriver(const DriverConfig& config, StreamFactory factory = serialStreamFactory());
  /// Switches the laser off (QT) when still connected.
  ~UrgDriver();
  UrgDriver(const UrgDriver&) = delete;
  UrgDriver& operator=(const UrgDriver&) = delete;
  /// Connects when not connected (open both ports, handshake); returns whether connected now.
  bool connect();
  /// Drops the connection (closing the ports), recording `reason`.
  void disconnect(const std::string& reason);
  bool connected() const;
  /// While connected and idle: disconnects when a link has hung up; returns connected().
  bool checkLink();
  /// A full scan; connects first when needed. The result says what went wrong; a lost link
  /// disconnects, so the next connect() starts over.
  ScanResult takeScan(int planes, const std::function<void(int, int)>& progress = nullptr);
  /// Thread-safe snapshot (may be called while a scan runs).
  DriverStats stats() const;
  const DriverConfig& config() const { return config_; }

 private:
  void updateLinkStats();

  DriverConfig config_;
  StreamFactory factory_;
  std::unique_ptr<ByteStream> urg_stream_, platform_stream_;
  std::unique_ptr<UrgDevice> urg_;
  std::unique_ptr<StepperPlatform> platform_;
  std::unique_ptr<RotatingScanner> scanner_;
  LinkStats retired_;  ///< link counters of earlier connections
  mutable std::mutex stats_mutex_;
  DriverStats stats_;
};

}  // namespace urg
}  // namespace scanstop
