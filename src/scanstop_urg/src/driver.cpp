#include "scanstop_urg/driver.h"

#include <utility>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/serial.h"

namespace scanstop {
namespace urg {

void DriverConfig::validate() const {
  if (urg_port.empty()) throw ConfigError("port (the URG's serial device) is empty");
  if (platform_port.empty()) throw ConfigError("platform/port (the rotation controller's serial device) is empty");
  urg.validate();
  scanner.validate();
  for (const auto& baud : {std::make_pair("baud", urg_baud), std::make_pair("platform/baud", platform_baud)})
    if (baud.second <= 0 || !isSupportedBaud(baud.second))
      throw ConfigError("parameter '" + std::string(baud.first) + "' = " + std::to_string(baud.second) +
                        " is not a supported rate (" + supportedBauds() + ")");
  requireInRange("platform/reply_timeout_s", stepper.reply_timeout_s, 0.01, 60.0, "s");
  requireInRange("platform/home_timeout_s", stepper.home_timeout_s, 0.01, 120.0, "s");
  requireInRange("platform/retries", stepper.retries, 0, 20);
  if (urg.first_step != scanner.geometry.first_step || urg.last_step != scanner.geometry.last_step)
    throw ConfigError("scanner steps disagree between the device and the geometry");
}

StreamFactory serialStreamFactory() {
  return [](const std::string& path, int baud) -> std::unique_ptr<ByteStream> {
    try {
      return std::make_unique<SerialPort>(path, baud);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(e.what());
    }
  };
}

UrgDriver::UrgDriver(const DriverConfig& config, StreamFactory factory)
    : config_(config), factory_(std::move(factory)) {
  config_.validate();
  stats_.state = "not connected yet";
}

UrgDriver::~UrgDriver() {
  if (!connected()) return;
  try {
    urg_->laserOff();
  } catch (const std::exception&) {
    // the device is gone or confused: nothing more to do on shutdown
  }
}

bool UrgDriver::connected() const { return scanner_ != nullptr; }

bool UrgDriver::checkLink() {
  if (!connected()) return false;
  if (!urg_stream_->alive()) {
    disconnect("the URG link " + config_.urg_port + " hung up (device unplugged?)");
  } else if (!platform_stream_->alive()) {
    disconnect("the platform link " + config_.platform_port + " hung up (device unplugged?)");
  }
  return connected();
}

void UrgDriver::updateLinkStats() {
  LinkStats s = retired_;
  if (urg_) {
    const LinkStats& l = urg_->stats();
    s.checksum_errors += l.checksum_errors;
    s.format_errors += l.format_errors;
    s.timeouts += l.timeouts;
    s.skipped_lines += l.skipped_lines;
    s.scip11_switches += l.scip11_switches;
  }
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.checksum_errors = s.checksum_errors;
  stats_.format_errors = s.format_errors;
  stats_.timeouts = s.timeouts;
  stats_.skipped_lines = s.skipped_lines;
  stats_.scip11_switches = s.scip11_switches;
}

void UrgDriver::disconnect(const std::string& reason) {
  const bool was = connected();
  updateLinkStats();
  if (urg_) {
    const LinkStats& l = urg_->stats();
    retired_.checksum_errors += l.checksum_errors;
    retired_.format_errors += l.format_errors;
    retired_.timeouts += l.timeouts;
    retired_.skipped_lines += l.skipped_lines;
    retired_.scip11_switches += l.scip11_switches;
  }
  scanner_.reset();
  platform_.reset();
  urg_.reset();
  platform_stream_.reset();
  urg_stream_.reset();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.connected = false;
  stats_.state = "disconnected: " + reason;
  stats_.last_error = reason;
  if (was) ++stats_.connection_losses;
}

bool UrgDriver::connect() {
  if (connected()) return true;
  std::string stage = "URG port " + config_.urg_port;
  try {
    urg_stream_ = factory_(config_.urg_port, config_.urg_baud);
    stage = "platform port " + config_.platform_port;
    platform_stream_ = factory_(config_.platform_port, config_.platform_baud);
    stage = "URG handshake on " + config_.urg_port;
    urg_ = std::make_unique<UrgDevice>(*urg_stream_, config_.urg);
    urg_->initialize();
    stage = "platform on " + config_.platform_port;
    platform_ = std::make_unique<StepperPlatform>(*platform_stream_, config_.stepper);
    const PlatformStatus ps = platform_->status();
    (void)ps;
    scanner_ = std::make_unique<RotatingScanner>(*urg_, *platform_, config_.scanner);
  } catch (const std::exception& e) {
    disconnect(stage + ": " + e.what());
    return false;
  }
  updateLinkStats();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.connected = true;
  stats_.state = "connected: " + urg_->info().summary();
  ++stats_.connects;
  return true;
}

ScanResult UrgDriver::takeScan(int planes, const std::function<void(int, int)>& progress) {
  if (!connect()) {
    ScanResult r;
    const DriverStats s = stats();
    r.message = "the rotating URG is not connected (" + s.state + ")";
    std::lock_guard<std::mutex> lock(stats_mutex_);
    ++stats_.scans_failed;
    return r;
  }
  ScanResult r = scanner_->takeScan(planes, [&](int done, int total) {
    updateLinkStats();
    if (progress) progress(done, total);
  });
  updateLinkStats();
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.planes_dropped += r.planes_dropped;
    stats_.plane_retries += r.plane_retries;
    if (r.success) {
      ++stats_.scans_ok;
      stats_.outliers_removed += r.outliers_removed;
      const uint64_t before = r.valid_points + r.outliers_removed;
      stats_.points_before_filter += before;
      stats_.last_outlier_share = before ? static_cast<double>(r.outliers_removed) / before : 0.0;
    } else {
      ++stats_.scans_failed;
      stats_.last_error = r.message;
    }
  }
  if (r.device_lost) disconnect(r.message);
  return r;
}

DriverStats UrgDriver::stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

}  // namespace urg
}  // namespace scanstop
