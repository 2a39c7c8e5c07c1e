#include "scanstop_urg/urg_device.h"

#include <chrono>
#include <sstream>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace urg {
namespace {

int intField(const std::map<std::string, std::string>& m, const std::string& key, int fallback) {
  const auto it = m.find(key);
  if (it == m.end()) return fallback;
  try {
    size_t used = 0;
    const int v = std::stoi(it->second, &used);
    return v;
  } catch (const std::exception&) {
    throw ScipError(ScipError::Kind::kFormat, "PP field " + key + ":" + it->second + " is not an integer");
  }
}

}  // namespace

void UrgConfig::validate() const {
  requireInRange("reply_timeout_s", reply_timeout_s, 0.001, 60.0, "s");
  requireInRange("scan_timeout_s", scan_timeout_s, 0.001, 60.0, "s");
  if (first_step < 0 || last_step < first_step || last_step > 9999)
    throw ConfigError("scanner steps " + std::to_string(first_step) + ".." + std::to_string(last_step) +
                      " must satisfy 0 <= first_step <= last_step");
}

std::string DeviceInfo::summary() const {
  std::ostringstream s;
  auto get = [](const std::map<std::string, std::string>& m, const std::string& k) {
    const auto it = m.find(k);
    return it == m.end() ? std::string("?") : it->second;
  };
  s << get(version, "PROD") << " serial " << get(version, "SERI") << ", firmware " << get(version, "FIRM") << ", DMIN "
    << dmin_mm << " mm, DMAX " << dmax_mm << " mm, steps " << amin << ".." << amax << " of " << ares << ", " << scan_rpm
    << " rpm, " << get(state, "STAT");
  return s.str();
}

UrgDevice::UrgDevice(ByteStream& stream, const UrgConfig& config) : channel_(stream, 128), config_(config) {
  config_.validate();
}

Reply UrgDevice::command(const std::string& command, double timeout_s, bool kv_lines) {
  const std::string line = command + ";" + std::to_string(tag_++ % 100000);
  ++stats_.commands;
  channel_.writeLine(line);
  ReplyReader reader(line, kv_lines);
  const auto start = std::chrono::steady_clock::now();
  std::string received;
  try {
    while (true) {
      const double left = timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (left <= 0 || !channel_.readLine(&received, left)) {
        ++stats_.timeouts;
        stats_.skipped_lines += reader.skippedLines();
        const std::string what = reader.echoSeen() ? "a half-read reply" : "no reply";
        channel_.drain(0.05, 0.5);
        throw ScipError(
            ScipError::Kind::kTimeout,
            what + " to '" + line + "' within " + std::to_string(timeout_s) + " s" +
                (reader.skippedLines() ? " (" + std::to_string(reader.skippedLines()) + " unexpected lines)" : ""));
      }
      if (reader.feedLine(received)) break;
    }
  } catch (const ScipError& e) {
    if (e.kind() == ScipError::Kind::kChecksum) ++stats_.checksum_errors;
    if (e.kind() == ScipError::Kind::kFormat) ++stats_.format_errors;
    if (e.kind() != ScipError::Kind::kTimeout) {
      stats_.skipped_lines += reader.skippedLines();
      channel_.drain(0.05, 0.5);  // skip the rest of the broken reply
    }
    throw;
  }
  stats_.skipped_lines += reader.skippedLines();
  Reply reply = reader.reply();
  if (reply.status() == "E") throw ScipError(ScipError::Kind::kScip11, "the URG answered '" + line + "' in SCIP 1.1");
  return reply;
}

Reply UrgDevice::expectOk(const std::string& cmd, double timeout_s, bool kv_lines, const std::string& also_ok) {
  Reply r = command(cmd, timeout_s, kv_lines);
  const std::string st = r.status();
  if (st != "00" && (also_ok.empty() || st != also_ok))
    throw ScipError(ScipError::Kind::kStatus,
                    "the URG refused " + cmd + ": status " + st + " (" + statusMeaning(cmd.substr(0, 2), st) + ")");
  return r;
}

void UrgDevice::switchToScip2() {
  // The switch command goes without a tag: a SCIP 1.1 device does not know tags.
  ++stats_.scip11_switches;
  channel_.writeLine("SCIP2.0");
  ReplyReader reader("SCIP2.0");
  std::string line;
  const auto start = std::chrono::steady_clock::now();
  while (true) {
    const double left =
        config_.reply_timeout_s - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (left <= 0 || !channel_.readLine(&line, left)) {
      ++stats_.timeouts;
      channel_.drain(0.05, 0.5);
      throw ScipError(ScipError::Kind::kTimeout, "no reply to SCIP2.0 (is this a URG-04LX?)");
    }
    try {
      if (reader.feedLine(line)) break;
    } catch (const ScipError&) {
      channel_.drain(0.05, 0.5);
      break;  // a SCIP 2.0 device answers 0Ee; the QT that follows tells
    }
  }
}

void UrgDevice::initialize() {
  // A crashed client may have left a stream running: flush, and drain until quiet.
  channel_.drain(0.05, 1.0);
  std::string problem;
  bool ok = false;
  for (int attempt = 0; attempt < 4 && !ok; ++attempt) {
    try {
      Reply r = command("QT", config_.reply_timeout_s);
      const std::string st = r.status();
      if (st == "00") {
        ok = true;
      } else if (st == "0E") {
        expectOk("TM2", config_.reply_timeout_s);  // time-stamp mode left on by another client
      } else {
        problem = "QT answered status " + st;
      }
    } catch (const ScipError& e) {
      problem = e.what();
      if (e.kind() == ScipError::Kind::kDisconnected) throw;
      if (e.kind() == ScipError::Kind::kScip11 || e.kind() == ScipError::Kind::kTimeout) {
        try {
          switchToScip2();
        } catch (const ScipError& e2) {
          if (e2.kind() == ScipError::Kind::kDisconnected) throw;
        }
      }
    }
  }
  if (!ok) throw ScipError(ScipError::Kind::kTimeout, "the URG does not answer in SCIP 2.0: " + problem);
  expectOk("RS", config_.reply_timeout_s);
  info_.version.clear();
  for (const auto& kv : parseKeyValues(expectOk("VV", config_.reply_timeout_s, true)))
    info_.version[kv.first] = kv.second;
  info_.parameters.clear();
  for (const auto& kv : parseKeyValues(expectOk("PP", config_.reply_timeout_s, true)))
    info_.parameters[kv.first] = kv.second;
  info_.state.clear();
  for (const auto& kv : parseKeyValues(expectOk("II", config_.reply_timeout_s, true)))
    info_.state[kv.first] = kv.second;
  const auto& pp = info_.parameters;
  info_.dmin_mm = intField(pp, "DMIN", 20);
  info_.dmax_mm = intField(pp, "DMAX", 5600);
  info_.ares = intField(pp, "ARES", 1024);
  info_.amin = intField(pp, "AMIN", 44);
  info_.amax = intField(pp, "AMAX", 725);
  info_.afrt = intField(pp, "AFRT", 384);
  info_.scan_rpm = intField(pp, "SCAN", 600);
  if (config_.first_step < info_.amin || config_.last_step > info_.amax)
    throw ScipError(ScipError::Kind::kStatus, "configured steps " + std::to_string(config_.first_step) + ".." +
                                                  std::to_string(config_.last_step) +
                                                  " lie outside the sensor's AMIN..AMAX " + std::to_string(info_.amin) +
                                                  ".." + std::to_string(info_.amax));
  expectOk("BM", config_.reply_timeout_s, false, "02");
}

ScanData UrgDevice::scan() {
  const std::string cmd = scanCommand(config_.first_step, config_.last_step, 1, 3);
  Reply r = command(cmd, config_.scan_timeout_s);
  if (r.status() == "10") {  // laser off (someone sent QT or RS): switch it on and scan again
    expectOk("BM", config_.reply_timeout_s, false, "02");
    r = command(cmd, config_.scan_timeout_s);
  }
  try {
    return decodeScanReply(r, config_.first_step, config_.last_step, 1, 3);
  } catch (const ScipError& e) {
    if (e.kind() == ScipError::Kind::kFormat) ++stats_.format_errors;
    throw;
  }
}

void UrgDevice::laserOff() { expectOk("QT", config_.reply_timeout_s); }

}  // namespace urg
}  // namespace scanstop
