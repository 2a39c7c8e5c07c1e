#pragma once
// For the tests that run a libFuzzer target and fail on a finding: what the run found, in a few lines
// that fit at the head of a test failure (a CI log keeps the head of a message), with the failing input
// in hex so that it can be replayed on another machine (`xxd -r -p > input && FUZZER input`).
#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>

namespace scanstop {

/// The lines of a libFuzzer log that say what went wrong (an invariant, a sanitizer or libFuzzer error,
/// an uncaught exception, the test unit's path) and the test unit's bytes in hex (at most 4096 of them).
inline std::string fuzzFinding(const std::string& log) {
  std::string found, unit;
  size_t start = 0;
  while (start < log.size()) {
    const size_t end = std::min(log.find('\n', start), log.size());
    const std::string line = log.substr(start, end - start);
    for (const char* key : {"invariant violated", "ERROR:", "SUMMARY:", "uncaught", "what():", "Test unit written to"})
      if (line.find(key) != std::string::npos) {
        found += "  " + line + "\n";
        break;
      }
    const size_t at = line.find("Test unit written to ");
    if (at != std::string::npos) unit = line.substr(at + 21);
    start = end + 1;
  }
  if (unit.empty()) return found;
  std::ifstream in(unit, std::ios::binary);
  if (!in) return found + "  (the input " + unit + " could not be read)\n";
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  static const char* const kHex = "0123456789abcdef";
  std::string dump;
  for (size_t i = 0; i < std::min<size_t>(bytes.size(), 4096); ++i) {
    dump += kHex[static_cast<unsigned char>(bytes[i]) >> 4];
    dump += kHex[static_cast<unsigned char>(bytes[i]) & 15];
  }
  return found + "  the input (" + std::to_string(bytes.size()) + " bytes, hex" +
         (bytes.size() > 4096 ? ", the first 4096" : "") + "): " + dump + "\n";
}

}  // namespace scanstop
