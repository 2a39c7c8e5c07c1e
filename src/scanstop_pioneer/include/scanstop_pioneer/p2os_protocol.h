#pragma once
/// The P2OS/ARCOS serial protocol of the Pioneer 2 DX (PROTOCOL_FACTS part 2): packet framing and
/// checksum, command encoding, a resynchronising packet parser, the standard SIP and the SYNC2
/// reply. ROS-free; used by the driver, the emulator and the fuzz target.
///
/// Units on the wire: positions in robot units (x DistConvFactor -> mm), headings in angle units
/// (4096 per turn), wheel velocities in mm/s (x VelConvFactor).

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace scanstop {
namespace pioneer {

constexpr uint8_t kHeader0 = 0xFA;
constexpr uint8_t kHeader1 = 0xFB;
/// Largest count byte P2OS accepts (payload + 2 checksum bytes).
constexpr size_t kMaxCount = 200;
/// Largest payload: kMaxCount - 2.
constexpr size_t kMaxPayload = kMaxCount - 2;

/// Client command numbers (PROTOCOL_FACTS 2.4). 0..2 are SYNC0..2 before the connection.
namespace cmd {
constexpr uint8_t kSync0 = 0, kSync1 = 1, kSync2 = 2;
constexpr uint8_t kPulse = 0, kOpen = 1, kClose = 2, kEnable = 4, kSetA = 5, kSetV = 6, kSetO = 7, kMove = 8,
                  kRotate = 9, kSetRV = 10, kVel = 11, kHead = 12, kDHead = 13, kRVel = 21, kSetRA = 23, kSonar = 28,
                  kStop = 29, kEStop = 55;
}  // namespace cmd

/// Argument type bytes.
constexpr uint8_t kArgInt = 0x3B;     ///< u16 LE, value >= 0
constexpr uint8_t kArgNegInt = 0x1B;  ///< |value| as u16 LE, value < 0
constexpr uint8_t kArgString = 0x2B;  ///< length byte + characters

/// Standard SIP packet types: 0x32 stopped, 0x33 moving (0x30..0x34 accepted as P2 does).
constexpr uint8_t kSipStopped = 0x32;
constexpr uint8_t kSipMoving = 0x33;
bool isStandardSipType(uint8_t type);

/// The P2OS checksum over a payload: big-endian byte pairs summed modulo 2^16, an odd last byte
/// XORed in.
uint16_t checksum(const uint8_t* payload, size_t n);
inline uint16_t checksum(const std::vector<uint8_t>& payload) { return checksum(payload.data(), payload.size()); }

/// Frames a payload: FA FB count payload checksum(high byte first). Throws std::invalid_argument
/// for an empty payload or one longer than kMaxPayload.
std::vector<uint8_t> framePacket(const std::vector<uint8_t>& payload);
/// A command without argument (SYNCn, PULSE, OPEN, CLOSE, STOP, E_STOP, SETO).
std::vector<uint8_t> commandPacket(uint8_t command);
/// A command with an integer argument (0x3B / 0x1B + |value| LE). Throws std::invalid_argument
/// when |value| > 32767.
std::vector<uint8_t> commandPacket(uint8_t command, int value);
/// A command with a string argument (0x2B + length + characters); at most 196 characters.
std::vector<uint8_t> commandPacket(uint8_t command, const std::string& value);

/// A decoded client command (the emulator's view).
struct ClientCommand {
  uint8_t number = 0;
  enum class Arg { kNone, kInt, kString } arg = Arg::kNone;
  int value = 0;     ///< for kInt, signed
  std::string text;  ///< for kString
};
/// Decodes a client command payload; returns false with a reason for a malformed argument.
bool decodeCommand(const uint8_t* payload, size_t n, ClientCommand& out, std::string* error = nullptr);

/// Splits a byte stream into packets: resynchronises on FA FB, rejects count bytes outside
/// [3, kMaxCount] and packets with a wrong checksum (skipping one byte and searching again, so a
/// dropped byte costs at most the packets it touches). Never grows beyond one packet of backlog.
class PacketParser {
 public:
  struct Stats {
    uint64_t packets = 0;          ///< valid packets returned
    uint64_t checksum_errors = 0;  ///< complete frames whose checksum did not match
    uint64_t bad_counts = 0;       ///< headers followed by an impossible count byte
    uint64_t skipped_bytes = 0;    ///< bytes discarded while searching for a header
  };

  /// Appends received bytes.
  void feed(const uint8_t* data, size_t n);
  /// Pops the next valid packet's payload (type/command byte first); false when none is complete.
  bool next(std::vector<uint8_t>& payload);
  /// Drops all buffered bytes (after a flush or reconnect); keeps the statistics.
  void clear();
  const Stats& stats() const { return stats_; }
  size_t buffered() const { return buffer_.size() - start_; }

 private:
  void compact();
  std::vector<uint8_t> buffer_;
  size_t start_ = 0;
  Stats stats_;
};

/// The standard SIP (PROTOCOL_FACTS 2.5), raw values as sent by the robot.
struct Sip {
  uint8_t type = kSipStopped;
  uint16_t x = 0;                                   ///< XPOS, low 15 bits [robot units]
  uint16_t y = 0;                                   ///< YPOS, low 15 bits [robot units]
  int16_t th = 0;                                   ///< THPOS [angle units]
  int16_t left_vel = 0;                             ///< [mm/s / VelConvFactor]
  int16_t right_vel = 0;                            ///< [mm/s / VelConvFactor]
  uint8_t battery = 0;                              ///< [0.1 V]
  uint8_t stall_bump_lo = 0;                        ///< bit 0 left wheel stall, bits 1..5 rear bumpers
  uint8_t stall_bump_hi = 0;                        ///< bit 0 right wheel stall, bits 1..5 front bumpers
  int16_t control = 0;                              ///< heading setpoint [angle units]
  uint16_t flags = 0;                               ///< bit 0 motors enabled
  uint8_t compass = 0;                              ///< [2 deg]
  std::vector<std::pair<uint8_t, uint16_t>> sonar;  ///< (number, range [RangeConvFactor units])
  bool has_io = false;                              ///< the gripper/analog/digital bytes were present
  uint16_t gripper = 0;
  uint8_t analog = 0, digin = 0, digout = 0;

  bool moving() const { return type == kSipMoving; }
  bool leftStall() const { return (stall_bump_lo & 0x01) != 0; }
  bool rightStall() const { return (stall_bump_hi & 0x01) != 0; }
  bool stalled() const { return leftStall() || rightStall(); }
  uint8_t rearBumpers() const { return (stall_bump_lo >> 1) & 0x1F; }
  uint8_t frontBumpers() const { return (stall_bump_hi >> 1) & 0x1F; }
  bool motorsEnabled() const { return (flags & 0x01) != 0; }
  double batteryVolts() const { return battery * 0.1; }
};

/// Decodes a standard SIP payload (type byte first). Fields after the sonar readings are optional;
/// bytes beyond them (newer firmware) are ignored. Returns false with a reason naming the field
/// when the payload is not a standard SIP or is truncated.
bool decodeSip(const uint8_t* payload, size_t n, Sip& out, std::string* error = nullptr);
/// Encodes a SIP payload (the emulator's side); positions are masked to 15 bits.
std::vector<uint8_t> encodeSip(const Sip& sip);

/// The SYNC2 reply: 0x02 + name, class and subclass, each NUL-terminated.
struct SyncInfo {
  std::string name;
  std::string robot_class;
  std::string subclass;
};
bool decodeSync2Reply(const uint8_t* payload, size_t n, SyncInfo& out, std::string* error = nullptr);
std::vector<uint8_t> encodeSync2Reply(const SyncInfo& info);

/// Formats bytes as "FA FB 03 ..." for messages and tests.
std::string hex(const std::vector<uint8_t>& bytes);

}  // namespace pioneer
}  // namespace scanstop
