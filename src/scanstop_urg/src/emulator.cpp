#include "scanstop_urg/emulator.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "scanstop_urg/platform.h"
#include "scanstop_urg/scip.h"

namespace scanstop {
namespace urg {
namespace {

constexpr int kAres = 1024, kAfrt = 384, kAmin = 44, kAmax = 725, kLastStep = 768;
constexpr uint32_t kDmin = 20, kDmax = 5600;

bool allDigits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

void BoxRoomScene::validate() const {
  const double m = std::abs(mount_offset) + std::abs(scanner_x_offset) + 0.05;
  if (!(x_min < x_max && y_min < y_max && z_max > 0.0)) throw std::invalid_argument("box room: empty extent");
  if (robot_x - m <= x_min || robot_x + m >= x_max || robot_y - m <= y_min || robot_y + m >= y_max)
    throw std::invalid_argument("box room: the robot must stand inside the room");
  if (scanner_height <= 0.0 || scanner_height >= z_max)
    throw std::invalid_argument("box room: the scanner height must lie between floor and ceiling");
}

uint32_t BoxRoomScene::value(double phi, int step) const {
  // Scanner geometry in base_link (the convention of scanstop_sim's ScannerConfig).
  const double theta = (step - kAfrt) * 2.0 * M_PI / kAres;
  const double h = std::sin(theta);
  const double dx = h * std::cos(phi), dy = h * std::sin(phi), dz = std::cos(theta);
  const double ox = scanner_x_offset + mount_offset * std::cos(phi), oy = mount_offset * std::sin(phi);
  // base_link -> world
  const double c = std::cos(robot_yaw), s = std::sin(robot_yaw);
  const double o[3] = {robot_x + c * ox - s * oy, robot_y + s * ox + c * oy, scanner_height};
  const double d[3] = {c * dx - s * dy, s * dx + c * dy, dz};
  const double lo[3] = {x_min, y_min, 0.0}, hi[3] = {x_max, y_max, z_max};
  double t = INFINITY;
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) continue;
    const double ta = ((d[a] > 0 ? hi[a] : lo[a]) - o[a]) / d[a];
    if (ta < t) {
      t = ta;
      axis = a;
    }
  }
  if (axis < 0 || !std::isfinite(t)) return 0;
  const double hy = o[1] + t * d[1], hz = o[2] + t * d[2];
  if (dark_patch && axis == 0 && d[0] > 0 && std::abs(hy) <= 0.3 && hz >= 1.0 && hz <= 1.4) return 1;
  const double mm = std::round(t * 1000.0);
  if (mm > kDmax) return 0;  // nothing within range: "object probably at ~22 m"
  if (mm < kDmin) return 19;
  return static_cast<uint32_t>(mm);
}

UrgEmulator::UrgEmulator(RangeFunction ranges) : ranges_(std::move(ranges)) {}

void UrgEmulator::powerCycle() {
  scip2_ = laser_on_ = tm_mode_ = stream_.active = false;
  clock_origin_ms_ = time_ms_;
}

uint32_t UrgEmulator::timestamp() const {
  return static_cast<uint32_t>(static_cast<uint64_t>(time_ms_ - clock_origin_ms_) & 0xFFFFFFu);
}

std::string UrgEmulator::reply(const std::string& echo, const std::string& status, const std::string& body) const {
  return echo + "\n" + withSum(status) + "\n" + body + "\n";
}

std::string UrgEmulator::kv(const std::string& key, const std::string& value) const {
  const std::string payload = key + ":" + value;
  return payload + ";" + scipSum(payload) + "\n";
}

UrgEmulator::Response UrgEmulator::handleLine(const std::string& line) {
  Response r;
  if (line.empty()) return r;
  if (!scip2_) {
    // SCIP 1.1: only the switch to SCIP 2.0 is understood; everything else is rejected with "E".
    if (line == "SCIP2.0") {
      scip2_ = true;
      r.bytes = line + "\n0\n\n";
    } else {
      r.bytes = line + "\nE\n\n";
    }
    return r;
  }
  const size_t semi = line.find(';');
  const std::string body = line.substr(0, semi);
  if (semi != std::string::npos) {
    const std::string tag = line.substr(semi + 1);
    if (tag.size() > 16) {
      r.bytes = reply(line, "0G");
      return r;
    }
  }
  if (body.size() < 2) {
    r.bytes = reply(line, "0E");
    return r;
  }
  const std::string cmd = body.substr(0, 2), params = body.substr(2);
  if (tm_mode_ && cmd != "TM" && cmd != "RS") {
    r.bytes = reply(line, "0E");
    return r;
  }
  if (body == "SCIP2.0") {
    r.bytes = reply(line, "0E");  // already in SCIP 2.0
  } else if (cmd == "VV" && params.empty()) {
    r.bytes =
        reply(line, "00",
              kv("VEND", "Hokuyo Automatic Co.,Ltd.") + kv("PROD", "SOKUIKI Sensor URG-04LX") +
                  kv("FIRM", "3.3.00,07/07/10(scanstop emulator)") + kv("PROT", "SCIP 2.0") + kv("SERI", "H0000042"));
  } else if (cmd == "PP" && params.empty()) {
    r.bytes =
        reply(line, "00",
              kv("MODL", "URG-04LX(Hokuyo Automatic Co.,Ltd.)") + kv("DMIN", "20") + kv("DMAX", "5600") +
                  kv("ARES", "1024") + kv("AMIN", "44") + kv("AMAX", "725") + kv("AFRT", "384") + kv("SCAN", "600"));
  } else if (cmd == "II" && params.empty()) {
    r.bytes =
        reply(line, "00",
              kv("MODL", "URG-04LX") + kv("LASR", laser_on_ ? "ON" : "OFF") + kv("SCSP", "Initial(600)[rpm]") +
                  kv("MESM", "Measuring by SCIP") + kv("SBPS", "USB only") + kv("TIME", encodeValue(timestamp(), 4)) +
                  kv("STAT", laser_fault_ ? "Laser malfunction" : "Sensor works well."));
  } else if (cmd == "BM" && params.empty()) {
    if (laser_fault_) {
      r.bytes = reply(line, "01");
    } else {
      r.bytes = reply(line, laser_on_ ? "02" : "00");
      laser_on_ = true;
    }
  } else if (cmd == "QT" && params.empty()) {
    laser_on_ = false;
    stream_.active = false;
    r.bytes = reply(line, "00");
  } else if (cmd == "RS" && params.empty()) {
    laser_on_ = tm_mode_ = stream_.active = false;
    clock_origin_ms_ = time_ms_;
    r.bytes = reply(line, "00");
  } else if (cmd == "TM") {
    if (params == "0") {
      tm_mode_ = true;
      r.bytes = reply(line, "00");
    } else if (params == "1") {
      r.bytes = tm_mode_ ? reply(line, "00", withSum(encodeValue(timestamp(), 4)) + "\n") : reply(line, "01");
    } else if (params == "2") {
      tm_mode_ = false;
      r.bytes = reply(line, "00");
    } else {
      r.bytes = reply(line, params.empty() ? "0C" : "0A");
    }
  } else if (cmd == "GD" || cmd == "GS") {
    return handleScan(line, cmd, params);
  } else if (cmd == "MD" || cmd == "MS") {
    return handleStream(line, cmd, params, semi == std::string::npos ? "" : line.substr(semi));
  } else if (cmd == "VV" || cmd == "PP" || cmd == "II" || cmd == "BM" || cmd == "QT" || cmd == "RS") {
    r.bytes = reply(line, "0A");  // parameters where none belong
  } else {
    r.bytes = reply(line, "0E");
  }
  return r;
}

std::string UrgEmulator::parseRange(const std::string& params, int* first, int* last, int* cluster) const {
  const std::string s_first = params.substr(0, 4), s_last = params.substr(4, 4), s_cluster = params.substr(8, 2);
  if (!allDigits(s_first)) return "01";
  if (!allDigits(s_last)) return "02";
  if (!allDigits(s_cluster)) return "03";
  *first = std::stoi(s_first);
  *last = std::stoi(s_last);
  *cluster = std::max(1, std::stoi(s_cluster));
  if (*last > kLastStep) return "04";
  if (*last < *first) return "05";
  return "";
}

std::string UrgEmulator::scanBody(int first, int last, int cluster, int chars) {
  const uint32_t limit = chars == 3 ? (1u << 18) - 1 : (1u << 12) - 1;
  std::string encoded;
  encoded.reserve(static_cast<size_t>((last - first + 1) * chars));
  for (int s = first; s <= last; s += cluster) {
    // A cluster reports the smallest valid value of its group, else the first error code.
    uint32_t best = 0;
    bool have_valid = false;
    uint32_t first_code = 0;
    for (int k = s; k < std::min(s + cluster, last + 1); ++k) {
      // Steps outside AMIN..AMAX are not measured (they look into the sensor housing).
      const uint32_t v = (k < kAmin || k > kAmax) ? 19u : ranges_(k);
      if (v >= kDmin) {
        if (!have_valid || v < best) best = v;
        have_valid = true;
      } else if (k == s) {
        first_code = v;
      }
    }
    encoded += encodeValue(std::min(have_valid ? best : first_code, limit), chars);
  }
  ++scans_;
  return withSum(encodeValue(timestamp(), 4)) + "\n" + encodeDataBlock(encoded);
}

UrgEmulator::Response UrgEmulator::handleScan(const std::string& echo, const std::string& cmd,
                                              const std::string& params) {
  Response r;
  if (params.size() != 10) {
    r.bytes = reply(echo, params.size() < 10 ? "0C" : "0A");
    return r;
  }
  int first = 0, last = 0, cluster = 1;
  const std::string problem = parseRange(params, &first, &last, &cluster);
  if (!problem.empty()) {
    r.bytes = reply(echo, problem);
    return r;
  }
  if (!laser_on_) {
    r.bytes = reply(echo, "10");
    return r;
  }
  r.bytes = reply(echo, "00", scanBody(first, last, cluster, cmd == "GD" ? 3 : 2));
  r.delay_s = scan_period_s_;
  r.scan = true;
  return r;
}

UrgEmulator::Response UrgEmulator::handleStream(const std::string& echo, const std::string& cmd,
                                                const std::string& params, const std::string& tag) {
  Response r;
  if (params.size() != 13) {
    r.bytes = reply(echo, params.size() < 13 ? "0C" : "0A");
    return r;
  }
  int first = 0, last = 0, cluster = 1;
  const std::string problem = parseRange(params.substr(0, 10), &first, &last, &cluster);
  if (!problem.empty()) {
    r.bytes = reply(echo, problem);
    return r;
  }
  if (!allDigits(params.substr(10, 1))) {
    r.bytes = reply(echo, "06");
    return r;
  }
  if (!allDigits(params.substr(11, 2))) {
    r.bytes = reply(echo, "07");
    return r;
  }
  laser_on_ = true;  // MD switches the laser on itself
  stream_.active = true;
  stream_.cmd = cmd;
  stream_.range = params.substr(0, 10);
  stream_.tag = tag;
  stream_.first = first;
  stream_.last = last;
  stream_.cluster = cluster;
  stream_.chars = cmd == "MD" ? 3 : 2;
  stream_.skip = params[10] - '0';
  stream_.remaining = std::stoi(params.substr(11, 2));
  stream_.endless = stream_.remaining == 0;
  r.bytes = reply(echo, "00");
  r.delay_s = scan_period_s_;
  return r;
}

UrgEmulator::Response UrgEmulator::nextStreamScan() {
  Response r;
  if (!stream_.active) return r;
  if (!stream_.endless) --stream_.remaining;
  // skip is one digit, remaining two (both parsed from digits)
  char count[32];
  std::snprintf(count, sizeof(count), "%d%02d", stream_.skip % 10, stream_.endless ? 0 : stream_.remaining % 100);
  const std::string echo = stream_.cmd + stream_.range + count + stream_.tag;
  r.bytes = reply(echo, "99", scanBody(stream_.first, stream_.last, stream_.cluster, stream_.chars));
  r.delay_s = scan_period_s_ * (stream_.skip + 1);
  r.scan = true;
  if (!stream_.endless && stream_.remaining <= 0) {  // the last scan: the stream ends, the laser goes off
    stream_.active = false;
    laser_on_ = false;
  }
  return r;
}

std::string StepperEmulator::handleLine(const std::string& line) {
  using namespace stepper;
  if (line.empty()) return "";
  if (!checkSum(line)) return formatReply("XX", kBadSum, "");
  const std::string body = line.substr(0, line.size() - 1);
  if (body.size() < 2) return formatReply("XX", kUnknownCommand, "");
  const std::string cmd = body.substr(0, 2), params = body.substr(2);
  auto fail = [&](int code) {
    error_ = code;
    return formatReply(cmd, code, "");
  };
  char buf[32];
  if (cmd == "HM" && params.empty()) {
    if (count_ <= 0) return fail(kNotConfigured);
    position_ = 0;
    homed_ = true;
    return formatReply(cmd, kOk, "");
  }
  if (cmd == "SC") {
    if (params.size() != 4 || !allDigits(params)) return fail(kBadParameter);
    const int n = std::stoi(params);
    if (n < 1 || n > kMaxCount) return fail(kBadParameter);
    count_ = n;
    homed_ = false;
    position_ = 0;
    return formatReply(cmd, kOk, "");
  }
  if (cmd == "ST" && params.empty()) {
    if (count_ <= 0) return fail(kNotConfigured);
    if (!homed_) return fail(kNotHomed);
    if (stalls_ > 0) {
      --stalls_;
      homed_ = false;  // a stalled motor has lost its position
      return fail(kStall);
    }
    if (position_ >= count_) return fail(kEndOfTravel);
    ++position_;
    std::snprintf(buf, sizeof(buf), "%04d", position_);
    return formatReply(cmd, kOk, buf);
  }
  if (cmd == "SS" && params.empty()) {
    std::snprintf(buf, sizeof(buf), "%04d%04d%d%02d", position_, count_, homed_ ? 1 : 0, error_);
    return formatReply(cmd, kOk, buf);
  }
  if (cmd == "ER" && params.empty()) {
    std::snprintf(buf, sizeof(buf), "%02d", error_);
    error_ = 0;
    return formatReply(cmd, kOk, buf);
  }
  return formatReply(cmd, kUnknownCommand, "");
}

double StepperEmulator::angle() const { return count_ > 0 ? position_ * M_PI / count_ : 0.0; }

void StepperEmulator::powerCycle() {
  count_ = position_ = error_ = 0;
  homed_ = false;
}

bool FaultInjector::apply(std::string& reply) {
  bool changed = false;
  if (corrupt_ > 0 && !reply.empty()) {
    --corrupt_;
    // Lines of the reply; corrupt the sum of the middle data line (else the status line).
    std::vector<size_t> ends;
    for (size_t i = 0; i < reply.size(); ++i)
      if (reply[i] == '\n') ends.push_back(i);
    // ends[0] = echo, ends[1] = status, ends[2..n-2] = data, last = blank
    size_t line = ends.size() >= 4 ? 2 + (ends.size() - 3) / 2 : 1;
    if (line >= ends.size()) line = ends.size() - 1;
    const size_t sum_pos = ends[line] - 1;
    if (line > 0 && sum_pos > ends[line - 1]) {
      char& c = reply[sum_pos];
      c = static_cast<char>(c == 0x6F ? 0x30 : c + 1);
      changed = true;
    }
  }
  if (drop_ > 0 && !reply.empty()) {
    --drop_;
    for (int k = 0; k < drop_bytes_ && !reply.empty(); ++k) {
      std::uniform_int_distribution<size_t> pos(0, reply.size() - 1);
      reply.erase(pos(rng_), 1);
    }
    changed = true;
  }
  if (truncate_ > 0 && reply.size() > 1) {
    --truncate_;
    reply.resize(reply.size() / 2);
    changed = true;
  }
  return changed;
}

}  // namespace urg
}  // namespace scanstop
