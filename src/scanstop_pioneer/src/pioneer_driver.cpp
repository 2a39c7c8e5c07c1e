#include "scanstop_pioneer/pioneer_driver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace pioneer {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3g s", s);
  return buf;
}

}  // namespace

double monotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void DriverConfig::validate() const {
  if (port.empty()) throw ConfigError("parameter 'port' is empty: give the robot's serial device");
  requireOneOf("baud", baud, {9600, 19200, 38400, 57600, 115200});
  robot.validate("robot/");
  motion.validate("motion/");
  requireInRange("reply_timeout_s", client.reply_timeout_s, 0.05, 10.0, "s");
  requireInRange("sync_attempts", client.sync_attempts, 1, 20);
  requireInRange("close_wait_s", client.close_wait_s, 0.0, 5.0, "s");
  requireInRange("sip_timeout_s", sip_timeout_s, 0.2, 10.0, "s");
  requireInRange("reconnect_period_s", reconnect_period_s, 0.05, 60.0, "s");
  // ARIA pulses after 500 ms; P2OS' watchdog stops the drives after 2 s without a packet.
  requireInRange("pulse_period_s", pulse_period_s, 0.05, 1.5, "s");
  requireInRange("cmd_vel_timeout_s", cmd_vel_timeout_s, 0.05, 10.0, "s");
  requireInRange("max_linear_speed_mps", max_linear_speed_mps, 0.0, robot.max_velocity_mps, "m/s");
  requireInRange("max_angular_speed_radps", max_angular_speed_radps, 0.0, robot.max_rot_velocity_radps, "rad/s");
  // max_linear_speed / max_angular_speed bound every speed the driver commands (sendVelocity clamps
  // to them as well): the motion primitives' cruise speeds must lie within.
  requireInRange("motion/linear_speed_mps", motion.linear_speed_mps, 0.01, max_linear_speed_mps, "m/s");
  requireInRange("motion/angular_speed_radps", motion.angular_speed_radps, 0.02, max_angular_speed_radps, "rad/s");
}

PioneerDriver::PioneerDriver(const DriverConfig& config) : config_(config), odometry_(config.robot) {
  config_.validate();
  client_ = std::make_unique<P2osClient>(port_, config_.client);
  status_.port = config_.port;
}

PioneerDriver::~PioneerDriver() { stop(); }

void PioneerDriver::log(int level, const std::string& text) {
  if (log_cb_) log_cb_(level, text);
}

void PioneerDriver::start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (running_) return;
  running_ = true;
  thread_ = std::thread(&PioneerDriver::run, this);
}

void PioneerDriver::stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!running_) return;
    running_ = false;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

bool PioneerDriver::sleepFor(double seconds) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait_for(lock, std::chrono::duration<double>(seconds), [this] { return !running_; });
  return running_;
}

DriverStatus PioneerDriver::status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

bool PioneerDriver::commandVelocity(double v_mps, double w_radps, std::string* reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto refuse = [&](const std::string& why) {
    if (reason) *reason = why;
    return false;
  };
  if (!std::isfinite(v_mps) || !std::isfinite(w_radps)) return refuse("velocity is not finite");
  if (status_.link != LinkState::kConnected) return refuse("not connected to the robot");
  if (status_.motion_active || request_) return refuse("a rotate/forward motion is running");
  if (!halted_.empty()) return refuse("refused: " + halted_);
  teleop_v_ = std::clamp(v_mps, -config_.max_linear_speed_mps, config_.max_linear_speed_mps);
  teleop_w_ = std::clamp(w_radps, -config_.max_angular_speed_radps, config_.max_angular_speed_radps);
  teleop_t_ = monotonicSeconds();
  status_.teleop_active = true;
  return true;
}

MotionResult PioneerDriver::rotate(double angle_rad) { return runMotion(MotionKind::kRotate, angle_rad); }
MotionResult PioneerDriver::forward(double distance_m) { return runMotion(MotionKind::kForward, distance_m); }

MotionResult PioneerDriver::runMotion(MotionKind kind, double target) {
  MotionResult failed;
  failed.outcome = MotionOutcome::kAborted;
  // Validate the target up front (same limits as the controller).
  try {
    MotionController probe(config_.motion, kind, target, MotionSample());
  } catch (const std::invalid_argument& e) {
    failed.message = e.what();
    return failed;
  }
  const double speed =
      kind == MotionKind::kRotate ? config_.motion.angular_speed_radps : config_.motion.linear_speed_mps;
  const double decel =
      kind == MotionKind::kRotate ? config_.motion.angular_decel_radps2 : config_.motion.linear_decel_mps2;
  const double limit_s = config_.motion.timeout_factor * (std::abs(target) / speed + speed / decel) +
                         config_.motion.timeout_extra_s + config_.motion.settle_timeout_s + config_.sip_timeout_s + 3.0;

  std::unique_lock<std::mutex> lock(mutex_);
  failed.odom = status_.odom;
  if (!running_ || status_.link != LinkState::kConnected || !status_.have_sip) {
    failed.message = "not connected to the robot on " + config_.port +
                     (status_.last_error.empty() ? std::string() : " (" + status_.last_error + ")");
    return failed;
  }
  if (status_.motion_active || request_) {
    failed.message = "another rotate/forward motion is running";
    return failed;
  }
  if (!halted_.empty()) {
    failed.message = "refused: " + halted_;
    return failed;
  }
  request_ = MotionRequest{kind, target};
  result_.reset();
  cancel_motion_ = false;
  status_.motion_active = true;
  status_.teleop_active = false;
  teleop_t_ = -1.0;
  const bool done = cv_.wait_for(lock, std::chrono::duration<double>(limit_s), [this] { return result_.has_value(); });
  if (!done) {
    // The I/O thread did not finish in time (it should always do): ask it to abort, wait briefly.
    cancel_motion_ = true;
    cancel_reason_ = "cancelled: the motion exceeded the driver's time limit";
    cv_.wait_for(lock, std::chrono::duration<double>(2.0), [this] { return result_.has_value(); });
  }
  if (result_) {
    MotionResult r = *result_;
    result_.reset();
    return r;
  }
  request_.reset();
  failed.message = "the driver did not finish the motion within " + seconds(limit_s);
  return failed;
}

void PioneerDriver::halt(const std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  halted_ = reason;
  status_.teleop_active = false;  // the I/O thread then sends STOP (setpoints were non-zero)
  teleop_t_ = -1.0;
  if (status_.motion_active || request_) {
    cancel_motion_ = true;
    cancel_reason_ = "stopped: " + reason;
  }
}

void PioneerDriver::allowMotion() {
  std::lock_guard<std::mutex> lock(mutex_);
  halted_.clear();
}

void PioneerDriver::run() {
  while (true) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!running_) break;
    }
    if (connectOnce()) serve();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!running_) break;
    }
    sleepFor(config_.reconnect_period_s);
  }
  if (port_.isOpen()) {
    client_->close();
    port_.close();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  status_.link = LinkState::kDisconnected;
  if (request_ || motion_) {
    if (motion_) motion_->abort("driver shut down", monotonicSeconds());
    finishMotion();
  }
}

bool PioneerDriver::connectOnce() {
  std::string error;
  try {
    port_.open(config_.port, config_.baud);
    const SyncInfo info = client_->connect();
    std::string note = client_->lastConnectNote();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      status_.link = LinkState::kConnected;
      status_.robot = info;
      status_.connect_note = note;
      status_.have_sip = false;
      status_.sip_time_s = monotonicSeconds();
      status_.connects++;
      status_.recoveries = client_->recoveries();
      status_.last_error.clear();
      odometry_.rebase(status_.odom);
    }
    sent_vel_ = sent_rvel_ = 0;
    sent_nonzero_ = false;
    last_send_t_ = monotonicSeconds();
    log(0, "connected to " + info.name + " (" + info.robot_class + " " + info.subclass + ") on " + config_.port +
               (note.empty() ? "" : ": " + note));
    if (info.subclass != config_.robot.subclass)
      log(1, "the robot reports subclass '" + info.subclass + "' but the conversion factors are configured for '" +
                 config_.robot.subclass + "' (parameter robot/subclass): odometry may be scaled wrongly");
    return true;
  } catch (const std::exception& e) {
    error = e.what();
  }
  port_.close();
  bool changed = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    changed = status_.last_error != error;
    status_.last_error = error;
    status_.link = LinkState::kDisconnected;
  }
  if (changed)
    log(2, "cannot connect to the robot: " + error + " (retrying every " + seconds(config_.reconnect_period_s) + ")");
  return false;
}

void PioneerDriver::serve() {
  std::vector<uint8_t> payload;
  try {
    while (true) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!running_) return;
      }
      // Drain every complete packet, then wait briefly for more.
      if (client_->receive(payload, 0.02)) handlePacket(payload, monotonicSeconds());
      const double now = monotonicSeconds();
      double sip_age = 0.0;
      bool start_motion = false, cancel = false, teleop = false;
      MotionRequest request{MotionKind::kRotate, 0.0};
      double tv = 0.0, tw = 0.0;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const PacketParser::Stats& st = client_->parserStats();
        status_.checksum_errors = st.checksum_errors;
        status_.bad_counts = st.bad_counts;
        status_.skipped_bytes = st.skipped_bytes;
        sip_age = now - status_.sip_time_s;
        if (request_ && !motion_ && status_.have_sip) {
          request = *request_;
          start_motion = true;
        }
        cancel = cancel_motion_;
        if (status_.teleop_active && now - teleop_t_ > config_.cmd_vel_timeout_s) {
          status_.teleop_active = false;
          status_.cmd_vel_timeouts++;
          log(1, "cmd_vel timeout: no velocity command for " + seconds(config_.cmd_vel_timeout_s) +
                     ", stopping the robot");
        }
        teleop = status_.teleop_active;
        tv = teleop_v_;
        tw = teleop_w_;
      }
      if (sip_age > config_.sip_timeout_s) {
        char buf[96];
        std::snprintf(buf, sizeof(buf), "no valid SIP from the robot for %.1f s", sip_age);
        linkLost(buf);
        return;
      }
      if (start_motion) {
        MotionSample s;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          const Sip& sip = status_.sip;
          s.t_s = now;
          s.pose = status_.odom;
          s.moving = sip.moving();
          s.v_mps = status_.v_mps;
          s.w_radps = status_.w_radps;
          s.motors_enabled = sip.motorsEnabled();
        }
        if (!s.motors_enabled) {
          // The motors were disabled (motor button, or the robot refused ENABLE at connect): enable
          // them for the commanded motion; if they stay disabled, the motion aborts and says so.
          client_->send(commandPacket(cmd::kEnable, 1));
          log(1, "the robot reports its motors disabled: sending ENABLE before the motion");
        }
        motion_ = std::make_unique<MotionController>(config_.motion, request.kind, request.target, s);
        std::lock_guard<std::mutex> lock(mutex_);
        request_.reset();
        if (motion_->finished()) finishMotion();
      }
      if (motion_ && cancel) {
        sendStop(false, now);
        std::string why;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          why = cancel_reason_;
        }
        motion_->abort(why, now);
        std::lock_guard<std::mutex> lock(mutex_);
        finishMotion();
      }
      // Setpoints: the motion drives the robot (from handlePacket); otherwise teleoperation or zero.
      if (!motion_) {
        if (teleop) {
          sendVelocity(tv, tw, now);
        } else if (sent_nonzero_) {
          sendStop(false, now);
        }
      }
      if (now - last_send_t_ >= config_.pulse_period_s) {
        if (sent_nonzero_) {
          // Re-send the setpoints (they double as the keep-alive).
          client_->send(commandPacket(cmd::kVel, sent_vel_));
          client_->send(commandPacket(cmd::kRVel, sent_rvel_));
        } else {
          client_->send(commandPacket(cmd::kPulse));
        }
        last_send_t_ = now;
      }
    }
  } catch (const std::exception& e) {
    linkLost(e.what());
  }
}

void PioneerDriver::sendVelocity(double v_mps, double w_radps, double now) {
  // The last guard, whatever computed the setpoint: never faster than the configured bounds.
  v_mps = std::isfinite(v_mps) ? std::clamp(v_mps, -config_.max_linear_speed_mps, config_.max_linear_speed_mps) : 0.0;
  w_radps = std::isfinite(w_radps)
                ? std::clamp(w_radps, -config_.max_angular_speed_radps, config_.max_angular_speed_radps)
                : 0.0;
  const int vel = static_cast<int>(std::lround(v_mps * 1000.0));
  const int rvel = static_cast<int>(std::lround(w_radps * kRadToDeg));
  if (vel == sent_vel_ && rvel == sent_rvel_ && (vel != 0 || rvel != 0) == sent_nonzero_) return;
  client_->send(commandPacket(cmd::kVel, vel));
  client_->send(commandPacket(cmd::kRVel, rvel));
  sent_vel_ = vel;
  sent_rvel_ = rvel;
  sent_nonzero_ = vel != 0 || rvel != 0;
  last_send_t_ = now;
}

void PioneerDriver::sendStop(bool emergency, double now) {
  client_->send(commandPacket(emergency ? cmd::kEStop : cmd::kStop));
  client_->send(commandPacket(cmd::kVel, 0));
  client_->send(commandPacket(cmd::kRVel, 0));
  sent_vel_ = sent_rvel_ = 0;
  sent_nonzero_ = false;
  last_send_t_ = now;
}

void PioneerDriver::handlePacket(const std::vector<uint8_t>& payload, double now) {
  if (!isStandardSipType(payload[0])) {
    std::lock_guard<std::mutex> lock(mutex_);
    status_.other_packets++;
    return;
  }
  Sip sip;
  std::string error;
  if (!decodeSip(payload.data(), payload.size(), sip, &error)) {
    std::lock_guard<std::mutex> lock(mutex_);
    status_.sip_decode_errors++;
    return;
  }
  MotionSample sample;
  DriverStatus snapshot;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    odometry_.update(sip);
    status_.sip = sip;
    status_.have_sip = true;
    status_.sip_time_s = now;
    status_.odom = odometry_.pose();
    status_.v_mps = odometry_.linearVelocity();
    status_.w_radps = odometry_.angularVelocity();
    status_.sips++;
    sample.t_s = now;
    sample.pose = status_.odom;
    sample.moving = sip.moving();
    sample.v_mps = status_.v_mps;
    sample.w_radps = status_.w_radps;
    sample.left_stall = sip.leftStall();
    sample.right_stall = sip.rightStall();
    sample.front_bumpers = sip.frontBumpers();
    sample.rear_bumpers = sip.rearBumpers();
    sample.motors_enabled = sip.motorsEnabled();
    snapshot = status_;
  }
  if (sip_cb_) sip_cb_(snapshot);
  if (!motion_) return;
  const MotionCommand c = motion_->update(sample);
  if (c.stop) {
    if (c.emergency || sent_nonzero_) sendStop(c.emergency, now);
  } else {
    sendVelocity(c.v_mps, c.w_radps, now);
  }
  if (motion_->finished()) {
    std::lock_guard<std::mutex> lock(mutex_);
    finishMotion();
  }
}

void PioneerDriver::finishMotion() {
  // Called with mutex_ held.
  MotionResult r;
  if (motion_) {
    r.success = motion_->success();
    r.collision = motion_->collision();
    r.outcome = motion_->outcome();
    r.message = motion_->message();
    r.achieved = motion_->achieved();
    r.duration_s = motion_->durationS();
    r.odom = motion_->lastPose();
  } else {
    r.message = "the link to the robot was lost before the motion started";
    r.odom = status_.odom;
  }
  motion_.reset();
  request_.reset();
  status_.motion_active = false;
  result_ = r;
  cv_.notify_all();
}

void PioneerDriver::linkLost(const std::string& reason) {
  // Best effort: if only the robot's replies are lost, it may still hear us; stop it before leaving
  // (P2OS' own watchdog stops the drives after 2 s otherwise).
  if (port_.isOpen()) {
    try {
      client_->send(commandPacket(cmd::kStop));
    } catch (const std::exception&) {
    }
  }
  port_.close();
  log(2, "link to the robot lost: " + reason + "; reconnecting");
  std::lock_guard<std::mutex> lock(mutex_);
  status_.link = LinkState::kDisconnected;
  status_.last_error = reason;
  status_.link_losses++;
  status_.have_sip = false;
  status_.teleop_active = false;
  if (motion_ || request_) {
    if (motion_) motion_->abort("link to the robot lost (" + reason + ")", monotonicSeconds());
    finishMotion();
  }
}

}  // namespace pioneer
}  // namespace scanstop
