#pragma once
/// The client side of a P2OS session on a byte stream: the SYNC0/1/2 handshake with recovery from
/// a session still open from an earlier connection, OPEN, PULSE and ENABLE, then packet I/O.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "scanstop_pioneer/p2os_protocol.h"
#include "scanstop_pioneer/serial_port.h"

namespace scanstop {
namespace pioneer {

/// The robot answered wrongly or not at all; what() says which step failed and what was seen.
class ProtocolError : public std::runtime_error {
 public:
  explicit ProtocolError(const std::string& message) : std::runtime_error(message) {}
};

struct ClientConfig {
  double reply_timeout_s = 0.5;  ///< [s] wait for each handshake reply
  int sync_attempts = 4;         ///< handshake attempts per connect() (each after a CLOSE)
  double close_wait_s = 0.4;     ///< [s] wait after CLOSE before flushing and restarting at SYNC0
  bool enable_motors = true;     ///< send ENABLE 1 after OPEN
};

class P2osClient {
 public:
  P2osClient(ByteStream& stream, const ClientConfig& config) : stream_(stream), config_(config) {}

  /// Runs the handshake and opens the session; returns the robot's SYNC2 identification. Throws
  /// ProtocolError when no handshake succeeded within the attempts, LinkError when the link broke.
  SyncInfo connect();
  /// Sends STOP and CLOSE (best effort: link errors are swallowed).
  void close();

  /// Frames and sends a packet (from commandPacket()).
  void send(const std::vector<uint8_t>& packet);
  /// Waits up to timeout_s for the next valid packet; false on timeout.
  bool receive(std::vector<uint8_t>& payload, double timeout_s);

  const PacketParser::Stats& parserStats() const { return parser_.stats(); }
  /// Handshakes that met a session still open (a SIP during sync) and closed it first.
  uint64_t recoveries() const { return recoveries_; }
  /// What the last connect() had to do, for the log ("closed a session still open ...").
  const std::string& lastConnectNote() const { return note_; }

 private:
  enum class Reply { kOk, kStillOpen, kTimeout };
  Reply await(uint8_t expected, std::vector<uint8_t>& payload, std::string& seen);
  void closeStaleSession();

  ByteStream& stream_;
  ClientConfig config_;
  PacketParser parser_;
  uint64_t recoveries_ = 0;
  std::string note_;
};

}  // namespace pioneer
}  // namespace scanstop
