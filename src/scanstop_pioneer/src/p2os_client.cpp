#include "scanstop_pioneer/p2os_client.h"

#include <chrono>
#include <cstdio>
#include <thread>

namespace scanstop {
namespace pioneer {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

void P2osClient::send(const std::vector<uint8_t>& packet) { stream_.write(packet.data(), packet.size()); }

bool P2osClient::receive(std::vector<uint8_t>& payload, double timeout_s) {
  const Clock::time_point t0 = Clock::now();
  uint8_t buf[256];
  for (;;) {
    if (parser_.next(payload)) return true;
    const double left = timeout_s - secondsSince(t0);
    if (left <= 0.0) return false;
    const size_t n = stream_.read(buf, sizeof(buf), left);
    if (n > 0) parser_.feed(buf, n);
  }
}

P2osClient::Reply P2osClient::await(uint8_t expected, std::vector<uint8_t>& payload, std::string& seen) {
  const Clock::time_point t0 = Clock::now();
  for (;;) {
    const double left = config_.reply_timeout_s - secondsSince(t0);
    if (left <= 0.0 || !receive(payload, left)) return Reply::kTimeout;
    if (payload[0] == kSipStopped || payload[0] == kSipMoving) return Reply::kStillOpen;
    if (payload[0] == expected) return Reply::kOk;
    seen = "unexpected packet " + hex(payload);  // ignore and keep waiting
  }
}

void P2osClient::closeStaleSession() {
  send(commandPacket(cmd::kClose));
  std::this_thread::sleep_for(std::chrono::duration<double>(config_.close_wait_s));
  stream_.flushInput();
  parser_.clear();
}

SyncInfo P2osClient::connect() {
  note_.clear();
  std::string last_problem = "no attempt made";
  for (int attempt = 1; attempt <= config_.sync_attempts; ++attempt) {
    stream_.flushInput();
    parser_.clear();
    std::vector<uint8_t> payload;
    bool restart = false;
    for (uint8_t step = cmd::kSync0; step <= cmd::kSync2 && !restart; ++step) {
      send(commandPacket(step));
      std::string seen;
      const Reply reply = await(step, payload, seen);
      if (reply == Reply::kOk) continue;
      restart = true;
      if (reply == Reply::kStillOpen) {
        ++recoveries_;
        last_problem = "SYNC" + std::to_string(step) + " answered by a SIP: a session was still open";
        note_ = "closed a session still open from an earlier connection";
      } else {
        char limit[32];
        std::snprintf(limit, sizeof(limit), "%.3g s", config_.reply_timeout_s);
        last_problem =
            "no reply to SYNC" + std::to_string(step) + " within " + limit + (seen.empty() ? "" : " (" + seen + ")");
      }
      // Either an earlier session is open or the robot is in an unknown state: close and restart.
      closeStaleSession();
    }
    if (restart) continue;
    SyncInfo info;
    std::string error;
    if (!decodeSync2Reply(payload.data(), payload.size(), info, &error)) {
      last_problem = error;
      closeStaleSession();
      continue;
    }
    send(commandPacket(cmd::kOpen));
    send(commandPacket(cmd::kPulse));
    if (config_.enable_motors) send(commandPacket(cmd::kEnable, 1));
    return info;
  }
  throw ProtocolError("P2OS handshake failed after " + std::to_string(config_.sync_attempts) +
                      " attempts: " + last_problem);
}

void P2osClient::close() {
  try {
    send(commandPacket(cmd::kStop));
    send(commandPacket(cmd::kClose));
  } catch (const LinkError&) {
  }
}

}  // namespace pioneer
}  // namespace scanstop
