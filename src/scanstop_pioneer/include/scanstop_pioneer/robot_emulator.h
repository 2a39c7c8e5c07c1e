#pragma once
/// A Pioneer 2 DX as seen over its serial port: the P2OS sync state machine (WAIT -> GOT0 -> GOT1
/// -> CONNECTED -> OPEN), SIPs every sip_period after OPEN, motors disabled until ENABLE 1, VEL /
/// RVEL / STOP / E_STOP / SETO / SETA / SETRA, wheel motion integrated with acceleration limits,
/// 15-bit position wrap, the 2 s watchdog, and injectable faults. ROS-free and time-driven (the
/// caller passes the time), so it runs in tests as well as behind a pseudo-terminal.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "scanstop_common/pose.h"
#include "scanstop_pioneer/odometry.h"
#include "scanstop_pioneer/p2os_protocol.h"

namespace scanstop {
namespace pioneer {

struct EmulatorConfig {
  RobotParams robot;  ///< conversion factors used to encode SIPs
  SyncInfo identity{"scanstop-emulator", "Pioneer", "p2dx"};
  double sip_period_s = 0.1;        ///< [s] standard SIP cycle
  double watchdog_s = 2.0;          ///< [s] drives stop without client packets
  double trans_accel_mps2 = 0.3;    ///< [m/s^2] SETA default
  double rot_accel_radps2 = 1.745;  ///< [rad/s^2] SETRA default (100 deg/s^2)
  double battery_v = 12.5;          ///< [V]
  uint32_t seed = 1;                ///< fault randomness
  double start_x_mm = 0.0;          ///< [mm] odometry counters at OPEN (e.g. near the
  double start_y_mm = 0.0;          ///<      15-bit wrap, 0x7FFF units = 27.5 m)
};

enum class EmulatorState { kWait, kGot0, kGot1, kConnected, kOpen };
const char* toString(EmulatorState state);

/// Faults the emulator can inject (set through RobotEmulator::faults() or command()).
struct EmulatorFaults {
  int corrupt_checksum = 0;      ///< the next N packets carry a wrong checksum
  int drop_bytes = 0;            ///< the next N packets lose one byte
  int garbage_bytes = 0;         ///< random bytes sent before the next packet
  double silent_until = -1;      ///< [s] no output at all before this time (input still heard)
  bool stall = false;            ///< the wheels are blocked: no motion, stall flags while driven
  bool encoder = false;          ///< encoders frozen: the robot moves, odometry does not change
  bool motor_power_off = false;  ///< motor power switched off: motors disabled, ENABLE has no effect
  uint8_t front_bumpers = 0;     ///< bumper bits 1..5 reported (front)
  uint8_t rear_bumpers = 0;      ///< (rear)
};

class RobotEmulator {
 public:
  explicit RobotEmulator(const EmulatorConfig& config);

  /// Processes bytes from the client received at time t [s].
  void receive(const uint8_t* data, size_t n, double t);
  /// Integrates the motion up to t and queues the SIPs due.
  void advance(double t);
  /// Takes the bytes to send to the client.
  std::vector<uint8_t> takeOutput();

  /// Puts the robot into the OPEN state as if an earlier client had left its session open.
  void leaveOpen(double t);
  /// Applies a text command: corrupt N | drop N | garbage N | silence S | stall on|off |
  /// encoder on|off | motors on|off | bump front|rear|off | still_open | battery V | status. Returns a reply line;
  /// throws std::invalid_argument naming the command that was not understood.
  std::string command(const std::string& line, double t);

  EmulatorFaults& faults() { return faults_; }
  EmulatorState state() const { return state_; }
  bool motorsEnabled() const { return motors_enabled_; }
  /// The true pose since the last OPEN / SETO [m, rad] (equals odometry unless encoder fault).
  const Pose2D& truePose() const { return true_pose_; }
  double linearVelocity() const { return v_mps_; }
  double angularVelocity() const { return w_radps_; }
  uint64_t packetsReceived() const { return packets_received_; }
  uint64_t sipsSent() const { return sips_sent_; }
  uint64_t sessionsOpened() const { return sessions_opened_; }
  bool watchdogTripped() const { return watchdog_tripped_; }
  std::string statusLine() const;

 private:
  void handle(const ClientCommand& c, double t);
  void queue(const std::vector<uint8_t>& payload, double t);
  void openSession(double t);
  void closeSession();
  Sip makeSip() const;

  EmulatorConfig config_;
  EmulatorFaults faults_;
  PacketParser parser_;
  std::mt19937 rng_;
  std::vector<uint8_t> output_;
  EmulatorState state_ = EmulatorState::kWait;
  bool motors_enabled_ = false;
  double time_ = 0.0, next_sip_ = 0.0, last_packet_t_ = 0.0;
  bool watchdog_tripped_ = false;
  double set_v_mps_ = 0.0, set_w_radps_ = 0.0;  ///< setpoints from VEL / RVEL
  double trans_accel_ = 0.0, rot_accel_ = 0.0;
  double v_mps_ = 0.0, w_radps_ = 0.0;  ///< actual
  Pose2D true_pose_;
  double odo_x_mm_ = 0.0, odo_y_mm_ = 0.0, odo_th_rad_ = 0.0;  ///< what the encoders count
  uint64_t packets_received_ = 0, sips_sent_ = 0, sessions_opened_ = 0;
};

}  // namespace pioneer
}  // namespace scanstop
