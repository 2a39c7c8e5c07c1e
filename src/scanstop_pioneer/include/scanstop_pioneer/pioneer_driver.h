#pragma once
/// The Pioneer driver core, ROS-free: one I/O thread owns the serial link. It connects (with
/// recovery of a session still open), keeps the link alive (PULSE / setpoint re-send), decodes SIPs
/// into odometry, detects a lost link (no valid SIP within sip_timeout) and reconnects, applies
/// teleoperation velocities with a command timeout, and runs the rotate/forward motion primitives.
/// The odom frame stays continuous across reconnects.

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "scanstop_pioneer/motion_controller.h"
#include "scanstop_pioneer/odometry.h"
#include "scanstop_pioneer/p2os_client.h"
#include "scanstop_pioneer/serial_port.h"

namespace scanstop {
namespace pioneer {

struct DriverConfig {
  std::string port;  ///< serial device (or the emulator's pty link)
  int baud = 9600;   ///< P2OS starts at 9600
  RobotParams robot;
  ClientConfig client;
  MotionConfig motion;
  double sip_timeout_s = 1.0;            ///< [s] no valid SIP this long: link lost, reconnect
  double reconnect_period_s = 1.0;       ///< [s] pause between connection attempts
  double pulse_period_s = 0.5;           ///< [s] send PULSE / re-send setpoints at least this often
  double cmd_vel_timeout_s = 0.5;        ///< [s] teleoperation stops when no command came this long
  double max_linear_speed_mps = 0.5;     ///< [m/s] teleoperation clamp
  double max_angular_speed_radps = 1.0;  ///< [rad/s] teleoperation clamp

  /// Throws ConfigError naming the parameter that is wrong.
  void validate() const;
};

enum class LinkState { kDisconnected, kConnected };

/// A snapshot of everything the node publishes.
struct DriverStatus {
  LinkState link = LinkState::kDisconnected;
  std::string port;
  SyncInfo robot;            ///< identification from the last SYNC2 reply
  std::string last_error;    ///< why the link was last lost or could not be opened
  std::string connect_note;  ///< what the last handshake had to do (recovery)
  bool have_sip = false;     ///< a SIP arrived since the last connect
  Sip sip;                   ///< the last accepted SIP
  double sip_time_s = 0.0;   ///< [s] monotonic time of that SIP
  Pose2D odom;               ///< base_link in odom [m, rad]
  double v_mps = 0.0, w_radps = 0.0;
  bool motion_active = false;
  bool teleop_active = false;
  uint64_t sips = 0, sip_decode_errors = 0, other_packets = 0;
  uint64_t checksum_errors = 0, bad_counts = 0, skipped_bytes = 0;
  uint64_t connects = 0, recoveries = 0, link_losses = 0, cmd_vel_timeouts = 0;
};

/// The result of a rotate / forward motion.
struct MotionResult {
  bool success = false;
  bool collision = false;
  MotionOutcome outcome = MotionOutcome::kAborted;
  std::string message;
  double achieved = 0.0;  ///< [rad] or [m] measured by odometry
  double duration_s = 0.0;
  Pose2D odom;  ///< final odometry pose
};

/// Monotonic seconds (steady clock).
double monotonicSeconds();

class PioneerDriver {
 public:
  using StatusCallback = std::function<void(const DriverStatus&)>;
  using LogCallback = std::function<void(int level, const std::string&)>;  ///< level 0 info, 1 warn, 2 error

  /// Validates the configuration (ConfigError).
  explicit PioneerDriver(const DriverConfig& config);
  ~PioneerDriver();
  PioneerDriver(const PioneerDriver&) = delete;
  PioneerDriver& operator=(const PioneerDriver&) = delete;

  /// Called from the I/O thread after every accepted SIP (keep it short).
  void setSipCallback(StatusCallback cb) { sip_cb_ = std::move(cb); }
  void setLogCallback(LogCallback cb) { log_cb_ = std::move(cb); }
  /// Starts / stops the I/O thread (stop sends STOP and CLOSE).
  void start();
  void stop();

  /// Teleoperation velocity [m/s, rad/s] (clamped). Refused while a motion runs or without a link.
  bool commandVelocity(double v_mps, double w_radps, std::string* reason = nullptr);
  /// Blocking motion primitives; never wait longer than the motion's timeout plus a margin.
  MotionResult rotate(double angle_rad);
  MotionResult forward(double distance_m);
  /// Safety stop (the ROS master is gone: nobody supervises the robot): aborts a running motion
  /// (its result says `reason`), ends teleoperation and, until allowMotion(), refuses new motions and
  /// velocity commands with `reason`. The I/O thread sends STOP.
  void halt(const std::string& reason);
  void allowMotion();

  DriverStatus status() const;
  const DriverConfig& config() const { return config_; }

 private:
  struct MotionRequest {
    MotionKind kind;
    double target;
  };
  MotionResult runMotion(MotionKind kind, double target);
  void run();
  bool connectOnce();
  void serve();
  void handlePacket(const std::vector<uint8_t>& payload, double now);
  void linkLost(const std::string& reason);
  void sendVelocity(double v_mps, double w_radps, double now);
  void sendStop(bool emergency, double now);
  void finishMotion();
  void log(int level, const std::string& text);
  bool sleepFor(double seconds);

  DriverConfig config_;
  SerialPort port_;
  std::unique_ptr<P2osClient> client_;
  OdometryIntegrator odometry_;

  mutable std::mutex mutex_;  ///< guards status_, requests, results and teleop setpoints
  std::condition_variable cv_;
  DriverStatus status_;
  bool running_ = false;
  std::thread thread_;
  std::optional<MotionRequest> request_;
  std::unique_ptr<MotionController> motion_;  ///< owned by the I/O thread; presence mirrored in status_
  std::optional<MotionResult> result_;
  bool cancel_motion_ = false;
  std::string cancel_reason_;  ///< what a cancelled motion's result says
  std::string halted_;         ///< non-empty: halt() reason, motions refused
  double teleop_v_ = 0.0, teleop_w_ = 0.0, teleop_t_ = -1.0;

  // I/O-thread state.
  int sent_vel_ = 0, sent_rvel_ = 0;
  bool sent_nonzero_ = false;
  double last_send_t_ = 0.0;

  StatusCallback sip_cb_;
  LogCallback log_cb_;
};

}  // namespace pioneer
}  // namespace scanstop
