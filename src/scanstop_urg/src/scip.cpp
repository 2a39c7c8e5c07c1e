#include "scanstop_urg/scip.h"

#include <cstdio>

namespace scanstop {
namespace urg {

const char* kindName(ScipError::Kind kind) {
  switch (kind) {
    case ScipError::Kind::kChecksum:
      return "checksum error";
    case ScipError::Kind::kFormat:
      return "malformed reply";
    case ScipError::Kind::kStatus:
      return "error status";
    case ScipError::Kind::kTimeout:
      return "timeout";
    case ScipError::Kind::kScip11:
      return "device in SCIP 1.1";
    case ScipError::Kind::kDisconnected:
      return "disconnected";
  }
  return "unknown";
}

char scipSum(std::string_view payload) {
  unsigned sum = 0;
  for (unsigned char c : payload) sum += c;
  return static_cast<char>((sum & 0x3F) + 0x30);
}

std::string withSum(std::string_view payload) {
  std::string line(payload);
  line.push_back(scipSum(payload));
  return line;
}

bool checkSum(std::string_view line, bool tolerant) {
  if (line.empty()) return false;
  const std::string_view payload = line.substr(0, line.size() - 1);
  const char sum = line.back();
  if (scipSum(payload) == sum) return true;
  return tolerant && !payload.empty() && scipSum(payload.substr(0, payload.size() - 1)) == sum;
}

std::string encodeValue(uint32_t value, int chars) {
  if (chars < 1 || chars > 4)
    throw std::invalid_argument("SCIP values have 1 to 4 characters, not " + std::to_string(chars));
  if (chars < 4 && value >= (1u << (6 * chars)))
    throw std::invalid_argument("value " + std::to_string(value) + " does not fit in " + std::to_string(chars) +
                                " SCIP characters");
  if (chars == 4 && value >= (1u << 24))
    throw std::invalid_argument("value " + std::to_string(value) + " does not fit in 4 SCIP characters");
  std::string text(static_cast<size_t>(chars), '0');
  for (int i = chars - 1; i >= 0; --i) {
    text[static_cast<size_t>(i)] = static_cast<char>((value & 0x3F) + 0x30);
    value >>= 6;
  }
  return text;
}

bool decodeValue(std::string_view text, uint32_t* value) {
  if (text.empty() || text.size() > 4) return false;
  uint32_t v = 0;
  for (unsigned char c : text) {
    if (c < 0x30 || c > 0x6F) return false;
    v = (v << 6) | (c - 0x30u);
  }
  *value = v;
  return true;
}

std::string encodeDataBlock(std::string_view encoded) {
  std::string out;
  out.reserve(encoded.size() + encoded.size() / 32 + 4);
  for (size_t pos = 0; pos < encoded.size(); pos += 64) {
    const std::string_view chunk = encoded.substr(pos, 64);
    out.append(chunk);
    out.push_back(scipSum(chunk));
    out.push_back('\n');
  }
  return out;
}

void LineSplitter::feed(const char* data, size_t size, const std::function<void(const std::string&)>& on_line) {
  for (size_t i = 0; i < size; ++i) {
    const char c = data[i];
    if (c == '\n') {
      if (overflow_) {
        overflow_ = false;  // the end of a garbage line: drop it
      } else {
        // Every CR before the LF: a command ended "...\r\r\n" must not keep CRs the device then echoes
        // (the host would not recognise its own echo; found by the SCIP fuzzer).
        while (!buffer_.empty() && buffer_.back() == '\r') buffer_.pop_back();
        const std::string line = std::move(buffer_);
        buffer_.clear();
        on_line(line);
      }
      continue;
    }
    if (overflow_) continue;
    if (buffer_.size() >= max_line_) {
      buffer_.clear();
      overflow_ = true;
      ++overflows_;
      continue;
    }
    buffer_.push_back(c);
  }
}

void LineSplitter::reset() {
  buffer_.clear();
  overflow_ = false;
}

std::string Reply::status() const {
  if (status_line.size() == 3) return status_line.substr(0, 2);
  return status_line;
}

ReplyReader::ReplyReader(std::string echo, bool kv_lines) : echo_(std::move(echo)), kv_lines_(kv_lines) {}

bool ReplyReader::feedLine(const std::string& line) {
  switch (state_) {
    case State::kEcho:
      if (line == echo_) {
        reply_.echo = line;
        state_ = State::kStatus;
      } else {
        ++skipped_;
      }
      return false;
    case State::kStatus:
      if (line == "0" || line == "E") {  // SCIP2.0 acknowledgement / SCIP 1.1 rejection: no sum
        reply_.status_line = line;
        state_ = State::kData;
        return false;
      }
      if (line.size() != 3) {
        state_ = State::kDone;
        throw ScipError(ScipError::Kind::kFormat,
                        "reply to '" + echo_ + "': status line '" + line + "' is not 2 characters and a sum");
      }
      if (!checkSum(line)) {
        state_ = State::kDone;
        throw ScipError(ScipError::Kind::kChecksum,
                        "reply to '" + echo_ + "': status line '" + line + "' has a wrong sum");
      }
      reply_.status_line = line;
      state_ = State::kData;
      return false;
    case State::kData:
      if (line.empty()) {
        state_ = State::kDone;
        return true;
      }
      if (reply_.status_line == "E" || reply_.status_line == "0") {
        reply_.data.push_back(line);  // SCIP 1.1 lines have no SCIP 2.0 sums
        return false;
      }
      if (kv_lines_) {
        // VV/PP/II: lenient (some firmware has a wrong SERI sum); a bad sum keeps the raw line.
        if (line.size() >= 2 && checkSum(line, true)) {
          reply_.data.push_back(line.substr(0, line.size() - 1));
        } else {
          reply_.data.push_back(line);
        }
        return false;
      }
      if (line.size() < 2) {
        state_ = State::kDone;
        throw ScipError(ScipError::Kind::kFormat, "reply to '" + echo_ + "': data line " +
                                                      std::to_string(reply_.data.size() + 1) + " is too short");
      }
      if (!checkSum(line)) {
        state_ = State::kDone;
        throw ScipError(ScipError::Kind::kChecksum, "reply to '" + echo_ + "': data line " +
                                                        std::to_string(reply_.data.size() + 1) + " has a wrong sum");
      }
      reply_.data.push_back(line.substr(0, line.size() - 1));
      return false;
    case State::kDone:
      return true;
  }
  return false;
}

std::string scanCommand(int first, int last, int cluster, int chars) {
  if (first < 0 || last > 9999 || last < first)
    throw std::invalid_argument("scan steps must satisfy 0 <= first <= last <= 9999");
  if (cluster < 0 || cluster > 99) throw std::invalid_argument("cluster must be in 0..99");
  if (chars != 2 && chars != 3) throw std::invalid_argument("scan values have 2 (GS) or 3 (GD) characters");
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%s%04d%04d%02d", chars == 3 ? "GD" : "GS", first, last, cluster);
  return buf;
}

int scanValueCount(int first, int last, int cluster) {
  const int c = cluster < 1 ? 1 : cluster;
  return (last - first + 1 + c - 1) / c;
}

ScanData decodeScanReply(const Reply& reply, int first, int last, int cluster, int chars) {
  const std::string status = reply.status();
  if (status == "E") throw ScipError(ScipError::Kind::kScip11, "the URG answered '" + reply.echo + "' in SCIP 1.1");
  if (status != "00")
    throw ScipError(ScipError::Kind::kStatus, "the URG refused '" + reply.echo + "': status " + status + " (" +
                                                  statusMeaning(reply.echo.substr(0, 2), status) + ")");
  const size_t n = static_cast<size_t>(scanValueCount(first, last, cluster));
  const size_t total = n * static_cast<size_t>(chars);
  const size_t lines = (total + 63) / 64;
  if (reply.data.size() != lines + 1)
    throw ScipError(ScipError::Kind::kFormat, "reply to '" + reply.echo + "': " + std::to_string(reply.data.size()) +
                                                  " data lines, expected a time line and " + std::to_string(lines));
  ScanData out;
  if (reply.data[0].size() != 4 || !decodeValue(reply.data[0], &out.timestamp_ms))
    throw ScipError(ScipError::Kind::kFormat,
                    "reply to '" + reply.echo + "': bad time stamp line '" + reply.data[0] + "'");
  std::string joined;
  joined.reserve(total);
  for (size_t i = 1; i < reply.data.size(); ++i) {
    const std::string& d = reply.data[i];
    const size_t expected = i < lines ? 64 : total - 64 * (lines - 1);
    if (d.size() != expected)
      throw ScipError(ScipError::Kind::kFormat, "reply to '" + reply.echo + "': data line " + std::to_string(i) +
                                                    " has " + std::to_string(d.size()) + " characters, expected " +
                                                    std::to_string(expected));
    joined += d;
  }
  out.values.resize(n);
  for (size_t k = 0; k < n; ++k) {
    if (!decodeValue(std::string_view(joined).substr(k * chars, static_cast<size_t>(chars)), &out.values[k]))
      throw ScipError(ScipError::Kind::kFormat, "reply to '" + reply.echo + "': value " + std::to_string(k) +
                                                    " has a character outside 0x30..0x6F");
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> parseKeyValues(const Reply& reply) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& line : reply.data) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos || colon == 0) continue;
    std::string value = line.substr(colon + 1);
    const size_t semi = value.rfind(';');
    if (semi != std::string::npos) value.resize(semi);
    out.emplace_back(line.substr(0, colon), value);
  }
  return out;
}

std::string statusMeaning(const std::string& command, const std::string& status) {
  if (status == "00") return "ok";
  if (status == "99") return "ok, scan data follows";
  if (status == "0A" || status == "0B") return "command error";
  if (status == "0C" || status == "0F") return "missing parameters";
  if (status == "0D" || status == "0E") return "undefined command";
  if (status == "0G" || status == "0H") return "bad tag";
  if (status == "0I") return "the sensor is in firmware-update mode";
  if (command == "BM") {
    if (status == "01") return "laser fault: the laser cannot be switched on";
    if (status == "02") return "the laser was already on";
  }
  if (command == "GD" || command == "GS" || command == "MD" || command == "MS") {
    if (status == "01") return "start step is not numeric";
    if (status == "02") return "end step is not numeric";
    if (status == "03") return "cluster count is not numeric";
    if (status == "04") return "end step out of range";
    if (status == "05") return "end step below start step";
    if (status == "06") return "scan interval is not numeric";
    if (status == "07") return "scan count is not numeric";
    if (status == "10") return "the laser is off (BM needed)";
    if (status.size() == 2 && status >= "50" && status <= "98") return "hardware fault";
  }
  return "unknown status";
}

const char* errorCodeMeaning(uint32_t code) {
  switch (code) {
    case 0:
      return "no object in range (probably ~22 m)";
    case 1:
    case 2:
      return "reflection too weak";
    case 6:
      return "others (possibly 5.7 m)";
    case 7:
      return "neighbouring steps in error";
    case 8:
      return "intensity difference between the two waves";
    case 9:
      return "same step failed in the previous two scans";
    case 18:
      return "strong reflector";
    case 19:
      return "step cannot be measured";
    default:
      break;
  }
  if (code >= 10 && code <= 17) return "other error";
  if (code < 20) return "unlisted error code";
  return "distance";
}

}  // namespace urg
}  // namespace scanstop
