#pragma once
/// Runs a RobotEmulator behind a pseudo-terminal (posix_openpt, raw mode): a client opens the
/// slave device (or a symlink to it) like the robot's serial port. Adds the link-level fault
/// "disconnect S" (the pty disappears for S seconds and comes back, the robot's session intact).

#include <atomic>
#include <mutex>
#include <string>
#include <thread>

#include "scanstop_pioneer/robot_emulator.h"

namespace scanstop {
namespace pioneer {

class PtyEmulator {
 public:
  /// link_path: a symlink to the slave device kept up to date (empty: none).
  PtyEmulator(const EmulatorConfig& config, const std::string& link_path);
  ~PtyEmulator();
  PtyEmulator(const PtyEmulator&) = delete;
  PtyEmulator& operator=(const PtyEmulator&) = delete;

  /// Opens the pty and starts the thread; throws std::runtime_error naming the failing call.
  void start();
  void stop();

  /// The slave device currently serving (e.g. /dev/pts/3); empty while disconnected.
  std::string slavePath() const;
  /// The path a client should open: the symlink if one was given, else the slave device.
  std::string devicePath() const;
  /// Applies a fault/control command (RobotEmulator::command plus "disconnect S"); returns the
  /// reply; throws std::invalid_argument when not understood.
  std::string command(const std::string& line);
  /// Runs fn(emulator) under the emulator's lock.
  template <typename Fn>
  auto with(Fn fn) {
    std::lock_guard<std::mutex> lock(mutex_);
    return fn(emulator_);
  }
  /// Seconds since start() (the emulator's clock).
  double now() const;

 private:
  void openPty();
  void closePty();
  void loop();

  RobotEmulator emulator_;
  std::string link_path_;
  mutable std::mutex mutex_;
  int master_ = -1, slave_keep_ = -1;
  std::string slave_path_;
  double reconnect_at_ = -1.0;
  double t0_ = 0.0;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace pioneer
}  // namespace scanstop
