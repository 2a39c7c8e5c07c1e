#pragma once
/// Device emulators (ROS-free, C++17 only): a URG-04LX that speaks SCIP 2.0 (and boots in SCIP 1.1)
/// and answers from a geometric scene, the stepper rotation controller of platform_protocol.h, and
/// the fault injector the urg_emulator executable applies to their replies. Deterministic: the same
/// commands give the same bytes, so tests can compare a scan taken under faults with a clean one.

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace scanstop {
namespace urg {

/// A closed box room (walls, floor z = 0, ceiling) with the robot standing in it; one wall carries
/// a dark patch that returns "reflection too weak" (error code 1). All lengths in metres.
struct BoxRoomScene {
  double x_min = -3.0, x_max = 3.0;                       ///< walls [m] (world frame)
  double y_min = -2.5, y_max = 2.5;                       ///< walls [m]
  double z_max = 2.5;                                     ///< ceiling [m]; the floor is z = 0
  double robot_x = 0.4, robot_y = -0.3, robot_yaw = 0.3;  ///< base_link in the world [m, rad]
  double scanner_height = 0.45;                           ///< rotation centre above the floor [m]
  double scanner_x_offset = 0.0;                          ///< rotation axis ahead of base_link [m]
  double mount_offset = 0.0;                              ///< optical centre off the rotation axis, along the plane [m]
  bool dark_patch = true;  ///< a 0.6 x 0.4 m patch on the x_max wall (y in [-0.3, 0.3], z in [1.0, 1.4])
  /// The URG value (mm, or an error code below 20) of step `step` when the platform is at `phi_rad`
  /// (0 = scan plane along the robot's x axis), for a URG with ARES 1024, AFRT 384, DMAX 5600.
  uint32_t value(double phi_rad, int step) const;
  /// Throws std::invalid_argument when the robot or the scanner is not inside the room.
  void validate() const;
};

/// The URG-04LX's SCIP state machine: SCIP 1.1 after power-up until "SCIP2.0", then VV PP II BM QT
/// RS TM0/1/2 GD GS MD MS with tags, the real status codes and sums. Scan values come from `ranges`.
/// Other commands are answered while an MD stream runs (whole messages, never mixed within one).
class UrgEmulator {
 public:
  /// Returns the value of `step` for the current scan (mm or an error code).
  using RangeFunction = std::function<uint32_t(int step)>;
  explicit UrgEmulator(RangeFunction ranges);

  struct Response {
    std::string bytes;     ///< what the device sends (empty: nothing)
    double delay_s = 0.0;  ///< how long the device needs before sending it (a scan takes 100 ms)
    bool scan = false;     ///< the reply carries scan data
  };
  /// Handles one received line (without LF).
  Response handleLine(const std::string& line);
  /// Power-cycles the sensor: SCIP 1.1, laser off, time stamp mode off, clock restarts.
  void powerCycle();
  /// Advances the internal millisecond clock.
  void advance(double dt_s) { time_ms_ += dt_s * 1000.0; }
  void setClockMs(double ms) { time_ms_ = ms; }
  bool scip2() const { return scip2_; }
  bool laserOn() const { return laser_on_; }
  void setLaserFault(bool fault) { laser_fault_ = fault; }
  void setScanPeriod(double s) { scan_period_s_ = s; }
  uint64_t scans() const { return scans_; }
  /// An MD/MS stream is running (it ends after its count, or on QT / RS).
  bool streaming() const { return stream_.active; }
  /// The next scan message of the running stream: echo with the scans remaining, 99b, time,
  /// data, blank line; delay_s is the time to the next one. Empty when no stream runs.
  Response nextStreamScan();

 private:
  struct Stream {
    bool active = false;
    std::string cmd, range, tag;  ///< "MD"/"MS", "ssssEEEEcc", ";tag" or ""
    int first = 0, last = 0, cluster = 1, chars = 3, skip = 0, remaining = 0;
    bool endless = false;  ///< nn = 00: until QT
  };
  /// Parses "ssssEEEEcc"; returns "" or the error status.
  std::string parseRange(const std::string& params, int* first, int* last, int* cluster) const;
  /// The time line and data block of one scan.
  std::string scanBody(int first, int last, int cluster, int chars);
  Response handleStream(const std::string& echo, const std::string& cmd, const std::string& params,
                        const std::string& tag);
  std::string reply(const std::string& echo, const std::string& status, const std::string& body = "") const;
  std::string kv(const std::string& key, const std::string& value) const;
  uint32_t timestamp() const;
  Response handleScan(const std::string& echo, const std::string& cmd, const std::string& params);

  RangeFunction ranges_;
  bool scip2_ = false, laser_on_ = false, tm_mode_ = false, laser_fault_ = false;
  double time_ms_ = 0.0, clock_origin_ms_ = 0.0;
  double scan_period_s_ = 0.1;
  uint64_t scans_ = 0;
  Stream stream_;
};

/// The stepper rotation controller (platform_protocol.h): home, step count, step, status, error.
class StepperEmulator {
 public:
  /// Handles one received line (without LF); returns the reply line with LF (empty: no reply).
  std::string handleLine(const std::string& line);
  /// Platform angle [rad]: position * pi / count.
  double angle() const;
  int position() const { return position_; }
  bool homed() const { return homed_; }
  /// Makes the next `n` ST commands fail with a stall (error 03).
  void injectStall(int n) { stalls_ += n; }
  void powerCycle();

 private:
  int count_ = 0, position_ = 0, error_ = 0, stalls_ = 0;
  bool homed_ = false;
};

/// Transport faults applied to reply bytes (urg_emulator's fault injection).
class FaultInjector {
 public:
  explicit FaultInjector(uint64_t seed = 7) : rng_(seed) {}
  /// The next `n` replies get one line with a wrong sum (a data line when there is one).
  void corruptChecksums(int n) { corrupt_ += n; }
  /// The next `n` replies each lose `bytes` bytes at random places.
  void dropBytes(int n, int bytes) {
    drop_ += n;
    drop_bytes_ = bytes;
  }
  /// The next `n` replies stop half-way (the rest is never sent).
  void truncate(int n) { truncate_ += n; }
  /// Applies the pending faults to one reply; returns true when it changed it.
  bool apply(std::string& reply);
  int pending() const { return corrupt_ + drop_ + truncate_; }

 private:
  int corrupt_ = 0, drop_ = 0, drop_bytes_ = 1, truncate_ = 0;
  std::mt19937_64 rng_;
};

}  // namespace urg
}  // namespace scanstop
