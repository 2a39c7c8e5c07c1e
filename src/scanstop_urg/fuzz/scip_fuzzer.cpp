// libFuzzer target for the SCIP 2.0 parser: arbitrary bytes go through the line splitter into
// reply readers (GD scan, KEY:value) and the scan decoder, and through the URG and stepper
// emulators' command parsers (whose replies and MD stream messages must parse back) and the
// stepper reply parser. Any crash, sanitizer report or hang is a bug.
// Build: see CMakeLists.txt (clang++ -fsanitize=fuzzer,address,undefined).
#include <cstddef>
#include <cstdint>
#include <string>

#include "scanstop_urg/emulator.h"
#include "scanstop_urg/platform.h"
#include "scanstop_urg/scip.h"

using namespace scanstop::urg;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  // 1. Replies: a GD reader, a 2-char GS reader with clustering and a KEY:value reader.
  {
    LineSplitter splitter(72);
    ReplyReader gd("GD0044072501"), gs("GS0100020003"), kv("PP", true);
    bool gd_done = false, gs_done = false, kv_done = false;
    splitter.feed(bytes, size, [&](const std::string& line) {
      try {
        if (!gd_done) gd_done = gd.feedLine(line);
      } catch (const ScipError&) {
        gd_done = true;
      }
      try {
        if (!gs_done) gs_done = gs.feedLine(line);
      } catch (const ScipError&) {
        gs_done = true;
      }
      try {
        if (!kv_done) kv_done = kv.feedLine(line);
      } catch (const ScipError&) {
        kv_done = true;
      }
      try {
        (void)stepper::parseReply(line);
      } catch (const PlatformError&) {
      }
    });
    if (gd.complete()) {
      try {
        const ScanData d = decodeScanReply(gd.reply(), 44, 725, 1, 3);
        if (d.values.size() != 682) __builtin_trap();
      } catch (const ScipError&) {
      }
    }
    if (gs.complete()) {
      try {
        const ScanData d = decodeScanReply(gs.reply(), 100, 200, 3, 2);
        if (d.values.size() != 34) __builtin_trap();
      } catch (const ScipError&) {
      }
    }
    if (kv.complete()) (void)parseKeyValues(kv.reply());
  }
  // 2. Commands: the device side parses the same bytes as host commands.
  {
    UrgEmulator urg([](int step) { return static_cast<uint32_t>(step * 3); });
    StepperEmulator stepper;
    urg.handleLine("SCIP2.0");
    LineSplitter splitter(72);
    splitter.feed(bytes, size, [&](const std::string& line) {
      const UrgEmulator::Response r = urg.handleLine(line);
      // Whatever the device answers must itself parse as a complete reply to that line.
      if (!r.bytes.empty() && (line.empty() || line.back() != '\r')) {
        LineSplitter back(4096);
        const std::string cc = line.substr(0, 2);
        ReplyReader reader(line, cc == "VV" || cc == "PP" || cc == "II");  // KEY:value;S lines
        bool done = false;
        try {
          back.feed(r.bytes.data(), r.bytes.size(), [&](const std::string& l) {
            if (!done) done = reader.feedLine(l);
          });
        } catch (const ScipError&) {
          __builtin_trap();  // the emulator produced a reply with a bad sum
        }
        if (!done) __builtin_trap();
      }
      if (urg.streaming()) {  // an MD/MS scan message must parse back too (status 99)
        const std::string m = urg.nextStreamScan().bytes;
        const std::string echo = m.substr(0, m.find('\n'));
        LineSplitter back(4096);
        ReplyReader reader(echo);
        bool done = false;
        try {
          back.feed(m.data(), m.size(), [&](const std::string& l) {
            if (!done) done = reader.feedLine(l);
          });
        } catch (const ScipError&) {
          __builtin_trap();
        }
        if (!done || reader.reply().status() != "99") __builtin_trap();
      }
      (void)stepper.handleLine(line);
    });
  }
  // 3. Value decoding of every 1..4-character window.
  for (size_t n = 1; n <= 4 && n <= size; ++n) {
    uint32_t v = 0;
    if (decodeValue(std::string_view(bytes, n), &v) && encodeValue(v, static_cast<int>(n)) != std::string(bytes, n))
      __builtin_trap();
  }
  return 0;
}
