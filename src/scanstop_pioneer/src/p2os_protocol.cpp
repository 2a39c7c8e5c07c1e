#include "scanstop_pioneer/p2os_protocol.h"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace scanstop {
namespace pioneer {
namespace {

void setError(std::string* error, const std::string& text) {
  if (error) *error = text;
}

uint16_t u16le(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
int16_t s16le(const uint8_t* p) { return static_cast<int16_t>(u16le(p)); }
void putU16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v & 0xFF));
  out.push_back(static_cast<uint8_t>(v >> 8));
}

}  // namespace

bool isStandardSipType(uint8_t type) { return type >= 0x30 && type <= 0x34; }

uint16_t checksum(const uint8_t* payload, size_t n) {
  uint32_t c = 0;
  size_t i = 0;
  for (; i + 1 < n; i += 2) c = (c + ((static_cast<uint32_t>(payload[i]) << 8) | payload[i + 1])) & 0xFFFF;
  if (i < n) c ^= payload[i];
  return static_cast<uint16_t>(c);
}

std::vector<uint8_t> framePacket(const std::vector<uint8_t>& payload) {
  if (payload.empty()) throw std::invalid_argument("P2OS packet: empty payload");
  if (payload.size() > kMaxPayload)
    throw std::invalid_argument("P2OS packet: payload of " + std::to_string(payload.size()) + " bytes exceeds " +
                                std::to_string(kMaxPayload));
  std::vector<uint8_t> out;
  out.reserve(payload.size() + 5);
  out.push_back(kHeader0);
  out.push_back(kHeader1);
  out.push_back(static_cast<uint8_t>(payload.size() + 2));
  out.insert(out.end(), payload.begin(), payload.end());
  const uint16_t c = checksum(payload);
  out.push_back(static_cast<uint8_t>(c >> 8));
  out.push_back(static_cast<uint8_t>(c & 0xFF));
  return out;
}

std::vector<uint8_t> commandPacket(uint8_t command) { return framePacket({command}); }

std::vector<uint8_t> commandPacket(uint8_t command, int value) {
  if (value > 32767 || value < -32767)
    throw std::invalid_argument("P2OS command " + std::to_string(command) + ": argument " + std::to_string(value) +
                                " outside [-32767, 32767]");
  std::vector<uint8_t> payload{command, value >= 0 ? kArgInt : kArgNegInt};
  putU16(payload, static_cast<uint16_t>(std::abs(value)));
  return framePacket(payload);
}

std::vector<uint8_t> commandPacket(uint8_t command, const std::string& value) {
  if (value.size() > kMaxPayload - 3)
    throw std::invalid_argument("P2OS command " + std::to_string(command) + ": string argument of " +
                                std::to_string(value.size()) + " characters is too long");
  std::vector<uint8_t> payload(3 + value.size());
  payload[0] = command;
  payload[1] = kArgString;
  payload[2] = static_cast<uint8_t>(value.size());
  for (size_t i = 0; i < value.size(); ++i) payload[3 + i] = static_cast<uint8_t>(value[i]);
  return framePacket(payload);
}

bool decodeCommand(const uint8_t* payload, size_t n, ClientCommand& out, std::string* error) {
  out = ClientCommand();
  if (n == 0) {
    setError(error, "empty command payload");
    return false;
  }
  out.number = payload[0];
  if (n == 1) return true;
  const uint8_t type = payload[1];
  if (type == kArgInt || type == kArgNegInt) {
    if (n < 4) {
      setError(error, "command " + std::to_string(out.number) + ": integer argument truncated (" + std::to_string(n) +
                          " bytes)");
      return false;
    }
    out.arg = ClientCommand::Arg::kInt;
    out.value = type == kArgInt ? u16le(payload + 2) : -static_cast<int>(u16le(payload + 2));
    return true;
  }
  if (type == kArgString) {
    if (n < 3 || n < 3u + payload[2]) {
      setError(error, "command " + std::to_string(out.number) + ": string argument truncated");
      return false;
    }
    out.arg = ClientCommand::Arg::kString;
    out.text.assign(reinterpret_cast<const char*>(payload + 3), payload[2]);
    return true;
  }
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%02X", type);
  setError(error, "command " + std::to_string(out.number) + ": unknown argument type " + buf);
  return false;
}

// ---------------------------------------------------------------------------------------------
void PacketParser::feed(const uint8_t* data, size_t n) { buffer_.insert(buffer_.end(), data, data + n); }

void PacketParser::clear() {
  buffer_.clear();
  start_ = 0;
}

void PacketParser::compact() {
  if (start_ == 0) return;
  if (start_ >= buffer_.size()) {
    buffer_.clear();
  } else if (start_ > 4096 || start_ * 2 > buffer_.size()) {
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
  } else {
    return;
  }
  start_ = 0;
}

bool PacketParser::next(std::vector<uint8_t>& payload) {
  for (;;) {
    // Search the header.
    while (start_ < buffer_.size()) {
      if (buffer_[start_] == kHeader0 && (start_ + 1 >= buffer_.size() || buffer_[start_ + 1] == kHeader1)) break;
      ++start_;
      ++stats_.skipped_bytes;
    }
    const size_t avail = buffer_.size() - start_;
    if (avail < 3) {
      compact();
      return false;
    }
    const size_t count = buffer_[start_ + 2];
    if (count < 3 || count > kMaxCount) {
      ++stats_.bad_counts;
      ++start_;  // resynchronise after the FA
      continue;
    }
    if (avail < 3 + count) {
      compact();
      return false;
    }
    const uint8_t* p = buffer_.data() + start_ + 3;
    const size_t n = count - 2;
    const uint16_t sent = static_cast<uint16_t>((p[n] << 8) | p[n + 1]);
    if (checksum(p, n) != sent) {
      ++stats_.checksum_errors;
      ++start_;
      continue;
    }
    payload.assign(p, p + n);
    start_ += 3 + count;
    ++stats_.packets;
    compact();
    return true;
  }
}

// ---------------------------------------------------------------------------------------------
bool decodeSip(const uint8_t* payload, size_t n, Sip& out, std::string* error) {
  out = Sip();
  if (n == 0) {
    setError(error, "SIP: empty payload");
    return false;
  }
  if (!isStandardSipType(payload[0])) {
    char buf[48];
    std::snprintf(buf, sizeof(buf), "SIP: packet type 0x%02X is not a standard SIP", payload[0]);
    setError(error, buf);
    return false;
  }
  constexpr size_t kFixed = 20;  // up to and including the sonar count byte
  if (n < kFixed) {
    setError(error, "SIP: " + std::to_string(n) + " bytes, truncated before the sonar count (needs " +
                        std::to_string(kFixed) + ")");
    return false;
  }
  out.type = payload[0];
  out.x = u16le(payload + 1) & 0x7FFF;
  out.y = u16le(payload + 3) & 0x7FFF;
  out.th = s16le(payload + 5);
  out.left_vel = s16le(payload + 7);
  out.right_vel = s16le(payload + 9);
  out.battery = payload[11];
  out.stall_bump_lo = payload[12];
  out.stall_bump_hi = payload[13];
  out.control = s16le(payload + 14);
  out.flags = u16le(payload + 16);
  out.compass = payload[18];
  const size_t sonars = payload[19];
  if (n < kFixed + 3 * sonars) {
    setError(error, "SIP: sonar count " + std::to_string(sonars) + " needs " + std::to_string(kFixed + 3 * sonars) +
                        " bytes, packet has " + std::to_string(n));
    return false;
  }
  out.sonar.reserve(sonars);
  size_t off = kFixed;
  for (size_t i = 0; i < sonars; ++i, off += 3) out.sonar.emplace_back(payload[off], u16le(payload + off + 1));
  if (n >= off + 5) {
    out.has_io = true;
    out.gripper = u16le(payload + off);
    out.analog = payload[off + 2];
    out.digin = payload[off + 3];
    out.digout = payload[off + 4];
  }
  return true;
}

std::vector<uint8_t> encodeSip(const Sip& sip) {
  std::vector<uint8_t> out;
  out.reserve(25 + 3 * sip.sonar.size());
  out.push_back(sip.type);
  putU16(out, sip.x & 0x7FFF);
  putU16(out, sip.y & 0x7FFF);
  putU16(out, static_cast<uint16_t>(sip.th));
  putU16(out, static_cast<uint16_t>(sip.left_vel));
  putU16(out, static_cast<uint16_t>(sip.right_vel));
  out.push_back(sip.battery);
  out.push_back(sip.stall_bump_lo);
  out.push_back(sip.stall_bump_hi);
  putU16(out, static_cast<uint16_t>(sip.control));
  putU16(out, sip.flags);
  out.push_back(sip.compass);
  out.push_back(static_cast<uint8_t>(sip.sonar.size()));
  for (const auto& s : sip.sonar) {
    out.push_back(s.first);
    putU16(out, s.second);
  }
  putU16(out, sip.gripper);
  out.push_back(sip.analog);
  out.push_back(sip.digin);
  out.push_back(sip.digout);
  return out;
}

bool decodeSync2Reply(const uint8_t* payload, size_t n, SyncInfo& out, std::string* error) {
  out = SyncInfo();
  if (n == 0 || payload[0] != cmd::kSync2) {
    setError(error, "SYNC2 reply: packet does not start with 0x02");
    return false;
  }
  std::string* fields[3] = {&out.name, &out.robot_class, &out.subclass};
  size_t i = 1;
  for (int f = 0; f < 3; ++f) {
    const size_t begin = i;
    while (i < n && payload[i] != 0) ++i;
    if (i >= n) {
      static const char* names[3] = {"name", "class", "subclass"};
      setError(error, std::string("SYNC2 reply: ") + names[f] + " is not NUL-terminated");
      return false;
    }
    fields[f]->assign(reinterpret_cast<const char*>(payload + begin), i - begin);
    ++i;
  }
  return true;
}

std::vector<uint8_t> encodeSync2Reply(const SyncInfo& info) {
  std::vector<uint8_t> out{cmd::kSync2};
  for (const std::string* s : {&info.name, &info.robot_class, &info.subclass}) {
    out.insert(out.end(), s->begin(), s->end());
    out.push_back(0);
  }
  return out;
}

std::string hex(const std::vector<uint8_t>& bytes) {
  std::string out;
  char buf[4];
  for (size_t i = 0; i < bytes.size(); ++i) {
    std::snprintf(buf, sizeof(buf), "%02X", bytes[i]);
    if (i) out += ' ';
    out += buf;
  }
  return out;
}

}  // namespace pioneer
}  // namespace scanstop
