#include "scanstop_pioneer/robot_emulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace scanstop {
namespace pioneer {
namespace {

double approach(double value, double target, double step) {
  if (value < target) return std::min(target, value + step);
  return std::max(target, value - step);
}

}  // namespace

const char* toString(EmulatorState state) {
  switch (state) {
    case EmulatorState::kWait:
      return "WAIT";
    case EmulatorState::kGot0:
      return "GOT0";
    case EmulatorState::kGot1:
      return "GOT1";
    case EmulatorState::kConnected:
      return "CONNECTED";
    case EmulatorState::kOpen:
      return "OPEN";
  }
  return "?";
}

RobotEmulator::RobotEmulator(const EmulatorConfig& config)
    : config_(config), rng_(config.seed), trans_accel_(config.trans_accel_mps2), rot_accel_(config.rot_accel_radps2) {
  config_.robot.validate("emulator robot/");
}

void RobotEmulator::receive(const uint8_t* data, size_t n, double t) {
  parser_.feed(data, n);
  std::vector<uint8_t> payload;
  while (parser_.next(payload)) {
    ClientCommand c;
    if (!decodeCommand(payload.data(), payload.size(), c)) continue;  // P2OS drops it silently
    ++packets_received_;
    last_packet_t_ = t;
    handle(c, t);
  }
}

void RobotEmulator::openSession(double t) {
  state_ = EmulatorState::kOpen;
  motors_enabled_ = false;  // motors are always disabled after connecting
  set_v_mps_ = set_w_radps_ = v_mps_ = w_radps_ = 0.0;
  true_pose_ = Pose2D();
  odo_x_mm_ = config_.start_x_mm;
  odo_y_mm_ = config_.start_y_mm;
  odo_th_rad_ = 0.0;
  next_sip_ = t;
  last_packet_t_ = t;
  ++sessions_opened_;
}

void RobotEmulator::closeSession() {
  state_ = EmulatorState::kWait;
  motors_enabled_ = false;
  set_v_mps_ = set_w_radps_ = v_mps_ = w_radps_ = 0.0;
}

void RobotEmulator::leaveOpen(double t) {
  if (state_ != EmulatorState::kOpen) openSession(t);
  motors_enabled_ = true;
}

void RobotEmulator::handle(const ClientCommand& c, double t) {
  switch (state_) {
    case EmulatorState::kWait:
      if (c.number == cmd::kSync0) {
        queue({cmd::kSync0}, t);
        state_ = EmulatorState::kGot0;
      }
      return;
    case EmulatorState::kGot0:
      if (c.number == cmd::kSync1) {
        queue({cmd::kSync1}, t);
        state_ = EmulatorState::kGot1;
      } else if (c.number == cmd::kSync0) {
        queue({cmd::kSync0}, t);
      } else {
        state_ = EmulatorState::kWait;
      }
      return;
    case EmulatorState::kGot1:
      if (c.number == cmd::kSync2) {
        queue(encodeSync2Reply(config_.identity), t);
        state_ = EmulatorState::kConnected;
      } else if (c.number == cmd::kSync0) {
        queue({cmd::kSync0}, t);
        state_ = EmulatorState::kGot0;
      } else {
        state_ = EmulatorState::kWait;
      }
      return;
    case EmulatorState::kConnected:
      // 0 is PULSE now, not SYNC0: a client restarting the handshake here is not answered.
      if (c.number == cmd::kOpen) openSession(t);
      if (c.number == cmd::kClose) closeSession();
      return;
    case EmulatorState::kOpen:
      break;
  }
  const double v = c.arg == ClientCommand::Arg::kInt ? c.value : 0.0;
  switch (c.number) {
    case cmd::kPulse:
    case cmd::kOpen:
      break;
    case cmd::kClose:
      closeSession();
      break;
    case cmd::kEnable:
      motors_enabled_ = c.value != 0 && !faults_.motor_power_off;
      break;
    case cmd::kVel:
      set_v_mps_ = v * 1e-3;
      break;
    case cmd::kRVel:
      set_w_radps_ = v * M_PI / 180.0;
      break;
    case cmd::kStop:
      set_v_mps_ = set_w_radps_ = 0.0;
      break;
    case cmd::kEStop:
      set_v_mps_ = set_w_radps_ = v_mps_ = w_radps_ = 0.0;
      break;
    case cmd::kSetO:
      true_pose_ = Pose2D();
      odo_x_mm_ = odo_y_mm_ = odo_th_rad_ = 0.0;
      break;
    case cmd::kSetA:
      if (v > 0) trans_accel_ = v * 1e-3;
      break;
    case cmd::kSetRA:
      if (v > 0) rot_accel_ = v * M_PI / 180.0;
      break;
    default:
      break;  // other commands are accepted and ignored
  }
}

void RobotEmulator::queue(const std::vector<uint8_t>& payload, double t) {
  if (t < faults_.silent_until) return;
  std::uniform_int_distribution<int> byte(0, 255);
  for (; faults_.garbage_bytes > 0; --faults_.garbage_bytes) output_.push_back(static_cast<uint8_t>(byte(rng_)));
  std::vector<uint8_t> packet = framePacket(payload);
  if (faults_.corrupt_checksum > 0) {
    --faults_.corrupt_checksum;
    packet[packet.size() - 1] ^= 0x5A;
    packet[packet.size() - 2] ^= 0xA5;
  }
  if (faults_.drop_bytes > 0) {
    --faults_.drop_bytes;
    std::uniform_int_distribution<size_t> pos(2, packet.size() - 1);
    packet.erase(packet.begin() + static_cast<std::ptrdiff_t>(pos(rng_)));
  }
  output_.insert(output_.end(), packet.begin(), packet.end());
}

void RobotEmulator::advance(double t) {
  const double dt = t - time_;
  time_ = t;
  if (state_ != EmulatorState::kOpen || dt <= 0.0) return;
  watchdog_tripped_ = t - last_packet_t_ > config_.watchdog_s;
  double target_v = set_v_mps_, target_w = set_w_radps_;
  if (!motors_enabled_ || watchdog_tripped_) target_v = target_w = 0.0;
  target_v = std::clamp(target_v, -config_.robot.max_velocity_mps, config_.robot.max_velocity_mps);
  target_w = std::clamp(target_w, -config_.robot.max_rot_velocity_radps, config_.robot.max_rot_velocity_radps);
  v_mps_ = approach(v_mps_, target_v, trans_accel_ * dt);
  w_radps_ = approach(w_radps_, target_w, rot_accel_ * dt);
  if (faults_.stall) v_mps_ = w_radps_ = 0.0;
  // Exact arc integration of the body motion.
  const double dth = w_radps_ * dt, ds = v_mps_ * dt;
  const double mid = true_pose_.yaw + 0.5 * dth;
  const double dx = ds * std::cos(mid), dy = ds * std::sin(mid);
  true_pose_ = Pose2D(true_pose_.x + dx, true_pose_.y + dy, normalizeAngle(true_pose_.yaw + dth));
  if (!faults_.encoder) {
    const double omid = odo_th_rad_ + 0.5 * dth;
    odo_x_mm_ += 1000.0 * ds * std::cos(omid);
    odo_y_mm_ += 1000.0 * ds * std::sin(omid);
    odo_th_rad_ = normalizeAngle(odo_th_rad_ + dth);
  }
  while (t >= next_sip_) {
    queue(encodeSip(makeSip()), t);
    ++sips_sent_;
    next_sip_ += config_.sip_period_s;
    if (next_sip_ < t - 1.0) next_sip_ = t;  // after a long pause, do not burst
  }
}

Sip RobotEmulator::makeSip() const {
  const RobotParams& p = config_.robot;
  Sip s;
  const bool driven = std::abs(v_mps_) > 1e-6 || std::abs(w_radps_) > 1e-6;
  const bool commanded = motors_enabled_ && (std::abs(set_v_mps_) > 1e-6 || std::abs(set_w_radps_) > 1e-6);
  s.type = driven || commanded ? kSipMoving : kSipStopped;
  // 15-bit position counters (wrap around every 0x8000 units).
  const auto units = [&](double mm) {
    const long u = std::lround(mm / p.dist_conv_mm);
    return static_cast<uint16_t>(((u % 0x8000) + 0x8000) % 0x8000);
  };
  s.x = units(odo_x_mm_);
  s.y = units(odo_y_mm_);
  long th = std::lround(odo_th_rad_ / p.angle_conv_rad) % 4096;
  if (th < 0) th += 4096;
  s.th = static_cast<int16_t>(th);
  const bool moving_encoders = !faults_.encoder;
  const double axle_mm = 2.0 / p.diff_conv;
  const double left = moving_encoders ? v_mps_ * 1000.0 - 0.5 * w_radps_ * axle_mm : 0.0;
  const double right = moving_encoders ? v_mps_ * 1000.0 + 0.5 * w_radps_ * axle_mm : 0.0;
  s.left_vel = static_cast<int16_t>(std::lround(left / p.vel_conv));
  s.right_vel = static_cast<int16_t>(std::lround(right / p.vel_conv));
  s.battery = static_cast<uint8_t>(std::clamp(std::lround(config_.battery_v * 10.0), 0L, 255L));
  const bool stalled = faults_.stall && commanded;
  s.stall_bump_lo = static_cast<uint8_t>((stalled ? 1 : 0) | ((faults_.rear_bumpers & 0x1F) << 1));
  s.stall_bump_hi = static_cast<uint8_t>((stalled ? 1 : 0) | ((faults_.front_bumpers & 0x1F) << 1));
  s.control = s.th;
  s.flags = motors_enabled_ ? 1 : 0;
  for (uint8_t i = 0; i < 4; ++i) s.sonar.emplace_back(i, static_cast<uint16_t>(std::lround(2000.0 / p.range_conv_mm)));
  s.has_io = true;
  return s;
}

std::vector<uint8_t> RobotEmulator::takeOutput() {
  std::vector<uint8_t> out;
  out.swap(output_);
  return out;
}

std::string RobotEmulator::statusLine() const {
  char buf[256];
  std::snprintf(
      buf, sizeof(buf), "state %s motors %s pose %.3f %.3f %.4f v %.3f w %.3f packets %llu sips %llu sessions %llu%s",
      toString(state_), motors_enabled_ ? "on" : "off", true_pose_.x, true_pose_.y, true_pose_.yaw, v_mps_, w_radps_,
      static_cast<unsigned long long>(packets_received_), static_cast<unsigned long long>(sips_sent_),
      static_cast<unsigned long long>(sessions_opened_), watchdog_tripped_ ? " watchdog" : "");
  return buf;
}

std::string RobotEmulator::command(const std::string& line, double t) {
  std::istringstream in(line);
  std::string name, arg;
  in >> name >> arg;
  const auto number = [&](double lo, double hi) {
    char* end = nullptr;
    const double v = std::strtod(arg.c_str(), &end);
    if (arg.empty() || *end != '\0' || !(v >= lo && v <= hi))
      throw std::invalid_argument("emulator command '" + line + "': argument must be a number in [" +
                                  std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  };
  const auto onOff = [&]() {
    if (arg == "on") return true;
    if (arg == "off") return false;
    throw std::invalid_argument("emulator command '" + line + "': argument must be on or off");
  };
  if (name == "corrupt") {
    faults_.corrupt_checksum = static_cast<int>(number(0, 1e6));
  } else if (name == "drop") {
    faults_.drop_bytes = static_cast<int>(number(0, 1e6));
  } else if (name == "garbage") {
    faults_.garbage_bytes = static_cast<int>(number(0, 1e6));
  } else if (name == "silence") {
    faults_.silent_until = t + number(0, 3600);
  } else if (name == "stall") {
    faults_.stall = onOff();
  } else if (name == "encoder") {
    faults_.encoder = onOff();
  } else if (name == "motors") {
    // The motor power switch: off disables the motors and ignores ENABLE; on allows ENABLE again.
    faults_.motor_power_off = !onOff();
    if (faults_.motor_power_off) motors_enabled_ = false;
  } else if (name == "bump") {
    if (arg == "front") {
      faults_.front_bumpers = 0x04;
    } else if (arg == "rear") {
      faults_.rear_bumpers = 0x04;
    } else if (arg == "off") {
      faults_.front_bumpers = faults_.rear_bumpers = 0;
    } else {
      throw std::invalid_argument("emulator command '" + line + "': argument must be front, rear or off");
    }
  } else if (name == "still_open") {
    leaveOpen(t);
  } else if (name == "battery") {
    config_.battery_v = number(0, 25.5);
  } else if (name == "status") {
    return statusLine();
  } else {
    throw std::invalid_argument(
        "emulator command '" + line +
        "' not understood (corrupt N, drop N, garbage N, silence S, disconnect S, stall on|off, "
        "encoder on|off, motors on|off, bump front|rear|off, still_open, battery V, status)");
  }
  return "ok " + line;
}

}  // namespace pioneer
}  // namespace scanstop
