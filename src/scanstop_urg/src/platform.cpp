#include "scanstop_urg/platform.h"

#include <cctype>
#include <cstdio>

namespace scanstop {
namespace urg {
namespace stepper {

const char* statusMeaning(int status) {
  switch (status) {
    case kOk:
      return "ok";
    case kNotHomed:
      return "not homed";
    case kBadParameter:
      return "bad parameter";
    case kStall:
      return "motor stall or index switch not found";
    case kEndOfTravel:
      return "end of travel (half a turn)";
    case kBadSum:
      return "the controller received a line with a bad sum";
    case kUnknownCommand:
      return "unknown command";
    case kNotConfigured:
      return "no step count set";
    default:
      return "unknown status";
  }
}

std::string formatCommand(const std::string& cmd, const std::string& params) { return withSum(cmd + params) + "\n"; }

std::string formatReply(const std::string& cmd, int status, const std::string& values) {
  char st[8];
  std::snprintf(st, sizeof(st), "%02d", status < 0 || status > 99 ? 99 : status);
  return withSum(cmd + st + values) + "\n";
}

Reply parseReply(const std::string& line) {
  if (line.size() < 5) throw PlatformError("platform reply '" + line + "' is too short", true);
  if (!checkSum(line)) throw PlatformError("platform reply '" + line + "' has a wrong sum", true);
  Reply r;
  r.cmd = line.substr(0, 2);
  if (!std::isdigit(static_cast<unsigned char>(line[2])) || !std::isdigit(static_cast<unsigned char>(line[3])))
    throw PlatformError("platform reply '" + line + "' has no 2-digit status", true);
  r.status = (line[2] - '0') * 10 + (line[3] - '0');
  r.values = line.substr(4, line.size() - 5);
  return r;
}

}  // namespace stepper

namespace {

int parseDigits(const std::string& text, size_t pos, size_t len, const std::string& what) {
  if (pos + len > text.size()) throw PlatformError("platform " + what + " is missing in '" + text + "'", true);
  int v = 0;
  for (size_t i = pos; i < pos + len; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(text[i])))
      throw PlatformError("platform " + what + " '" + text.substr(pos, len) + "' is not numeric", true);
    v = v * 10 + (text[i] - '0');
  }
  return v;
}

}  // namespace

StepperPlatform::StepperPlatform(ByteStream& stream, const StepperConfig& config)
    : channel_(stream, 64), config_(config) {}

stepper::Reply StepperPlatform::transact(const std::string& cmd, const std::string& params, double timeout_s) {
  std::string last_problem;
  for (int attempt = 0; attempt <= config_.retries; ++attempt) {
    if (attempt > 0) channel_.drain(0.02, 0.2);
    try {
      channel_.write(stepper::formatCommand(cmd, params));
    } catch (const ScipError& e) {
      throw PlatformError("platform: " + std::string(e.what()), false, true);
    }
    std::string line;
    bool got = false;
    try {
      // Skip stale replies to earlier commands.
      while ((got = channel_.readLine(&line, timeout_s))) {
        if (line.size() >= 2 && (line.compare(0, 2, cmd) == 0 || line.compare(0, 2, "XX") == 0)) break;
      }
    } catch (const ScipError& e) {
      throw PlatformError("platform: " + std::string(e.what()), false, true);
    }
    if (!got) {
      last_problem = "no reply to " + cmd + " within " + std::to_string(timeout_s) + " s";
      if (cmd == "ST") break;  // never re-send a step blindly: the caller checks the position
      continue;
    }
    stepper::Reply r;
    try {
      r = stepper::parseReply(line);
    } catch (const PlatformError& e) {
      last_problem = e.what();
      if (cmd == "ST") break;
      continue;
    }
    if (r.status == stepper::kBadSum && attempt < config_.retries) {
      last_problem = "the controller received a corrupted " + cmd;
      continue;
    }
    if (r.status != stepper::kOk)
      throw PlatformError("platform refused " + cmd + params + ": status " + std::to_string(r.status) + " (" +
                              stepper::statusMeaning(r.status) + ")",
                          false);
    return r;
  }
  throw PlatformError("platform: " + last_problem, true, true);
}

void StepperPlatform::prepare(int planes) {
  if (planes < 1 || planes > stepper::kMaxCount)
    throw PlatformError(
        "platform: " + std::to_string(planes) + " planes is outside 1.." + std::to_string(stepper::kMaxCount), false);
  char buf[8];
  std::snprintf(buf, sizeof(buf), "%04d", planes);
  transact("ER", "", config_.reply_timeout_s);  // clear an old latched error
  transact("SC", buf, config_.reply_timeout_s);
  transact("HM", "", config_.home_timeout_s);
  const PlatformStatus s = status();
  if (!s.homed || s.position != 0 || s.count != planes)
    throw PlatformError("platform did not reach plane 0 of " + std::to_string(planes) + " after homing (position " +
                            std::to_string(s.position) + ", count " + std::to_string(s.count) + ")",
                        false);
}

int StepperPlatform::advance() {
  const PlatformStatus before = status();
  try {
    const stepper::Reply r = transact("ST", "", config_.reply_timeout_s);
    return parseDigits(r.values, 0, 4, "position");
  } catch (const PlatformError& e) {
    if (!e.transient()) throw;
    // The reply was lost: ask where the platform is, and step again only if it did not move.
    const PlatformStatus now = status();
    if (now.position == before.position + 1) return now.position;
    if (now.position != before.position || !now.homed)
      throw PlatformError("platform lost its position during a step", false);
    const stepper::Reply r = transact("ST", "", config_.reply_timeout_s);
    return parseDigits(r.values, 0, 4, "position");
  }
}

PlatformStatus StepperPlatform::status() {
  const stepper::Reply r = transact("SS", "", config_.reply_timeout_s);
  if (r.values.size() != 11) throw PlatformError("platform status '" + r.values + "' is not 11 digits", true);
  PlatformStatus s;
  s.position = parseDigits(r.values, 0, 4, "position");
  s.count = parseDigits(r.values, 4, 4, "count");
  s.homed = parseDigits(r.values, 8, 1, "homed flag") == 1;
  s.error = parseDigits(r.values, 9, 2, "error");
  return s;
}

void StepperPlatform::park() { transact("HM", "", config_.home_timeout_s); }

}  // namespace urg
}  // namespace scanstop
