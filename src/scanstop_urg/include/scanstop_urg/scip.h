#pragma once
/// SCIP 2.0 codec for the Hokuyo URG-04LX (PROTOCOL_FACTS part 1): line sums, 2/3/4-character
/// value encoding, data blocks cut into 64-character lines, a line splitter and a reply reader that
/// resynchronises on the echo. Pure C++17 (no ROS, no Eigen) so that the fuzz target can build it
/// with clang alone.

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace scanstop {
namespace urg {

/// A protocol failure, classified so that the caller can count it and decide to retry or reconnect.
class ScipError : public std::runtime_error {
 public:
  enum class Kind {
    kChecksum,      ///< a line's sum did not match (transmission error)
    kFormat,        ///< a reply that does not parse (wrong length, bad character, missing line)
    kStatus,        ///< the device answered with an error status
    kTimeout,       ///< no (complete) reply within the timeout
    kScip11,        ///< the device talks SCIP 1.1 (it was power-cycled)
    kDisconnected,  ///< the serial link is gone
  };
  ScipError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }
  /// A transmission error: re-reading the same data may succeed.
  bool transient() const { return kind_ == Kind::kChecksum || kind_ == Kind::kFormat || kind_ == Kind::kTimeout; }

 private:
  Kind kind_;
};

const char* kindName(ScipError::Kind kind);

/// The SCIP sum of `payload`: (sum of the bytes & 0x3F) + 0x30.
char scipSum(std::string_view payload);
/// `payload` followed by its sum character.
std::string withSum(std::string_view payload);
/// Checks a line (without LF) whose last character is the sum of the characters before it. With
/// `tolerant`, a sum computed without the last payload character is accepted too (urg_c does; the
/// KEY:value;S lines of VV/PP/II use it to leave out the ';'). Returns false for an empty line.
bool checkSum(std::string_view line, bool tolerant = false);

/// Encodes `value` in `chars` characters of 6 bits (+0x30, most significant first); chars in 1..4.
/// Throws std::invalid_argument when the value does not fit.
std::string encodeValue(uint32_t value, int chars);
/// Decodes 1..4 characters; false when a character is outside 0x30..0x6F or the length is wrong.
bool decodeValue(std::string_view text, uint32_t* value);

/// Cuts an encoded value string into data lines of at most 64 characters, each with its sum and LF.
std::string encodeDataBlock(std::string_view encoded);

/// Splits a byte stream into LF-terminated lines (LF removed; any CRs right before the LF removed too).
/// A line longer than `max_line` is garbage: it is dropped up to the next LF and counted.
class LineSplitter {
 public:
  explicit LineSplitter(size_t max_line = 128) : max_line_(max_line) {}
  /// Adds bytes; calls `on_line` for every completed line.
  void feed(const char* data, size_t size, const std::function<void(const std::string&)>& on_line);
  /// Forgets a partial line (after a timeout or a reconnect).
  void reset();
  bool partial() const { return !buffer_.empty() || overflow_; }
  uint64_t overflows() const { return overflows_; }

 private:
  size_t max_line_;
  std::string buffer_;
  bool overflow_ = false;
  uint64_t overflows_ = 0;
};

/// One reply: the echo, the status line (as received, sum included when there is one) and the
/// payloads of the data lines (sums checked and removed).
struct Reply {
  std::string echo;
  std::string status_line;
  std::vector<std::string> data;  ///< data line payloads, sums removed
  /// The 1-2 character status code ("00", "0E", "0" for SCIP2.0, "E" from a SCIP 1.1 device).
  std::string status() const;
};

/// Collects one reply line by line. Lines before the expected echo (a stale or half-read earlier
/// reply, garbage) are skipped and counted. The status line's sum is checked, and every data
/// line's sum (strictly for data blocks, tolerantly for KEY:value lines) unless the reply is
/// the SCIP 1.1 "E" rejection.
class ReplyReader {
 public:
  /// `echo`: the command line as sent, without LF; `kv_lines`: the data lines are KEY:value;S.
  explicit ReplyReader(std::string echo, bool kv_lines = false);
  /// Feeds one line; returns true when the reply is complete (the empty line arrived). Throws
  /// ScipError(kChecksum/kFormat) on a bad status or data line; the reader is then finished and
  /// the rest of the reply must be skipped by the caller (resynchronisation).
  bool feedLine(const std::string& line);
  bool complete() const { return state_ == State::kDone; }
  bool echoSeen() const { return state_ != State::kEcho; }
  size_t skippedLines() const { return skipped_; }
  const Reply& reply() const { return reply_; }

 private:
  enum class State { kEcho, kStatus, kData, kDone };
  std::string echo_;
  bool kv_lines_;
  State state_ = State::kEcho;
  size_t skipped_ = 0;
  Reply reply_;
};

/// The result of a GD/GS scan: the 24-bit time stamp [ms] and one raw value per (cluster of) step(s).
struct ScanData {
  uint32_t timestamp_ms = 0;
  std::vector<uint32_t> values;  ///< mm, or an error code below DMIN
};

/// The GD (3-char) / GS (2-char) request line for steps first..last with `cluster` (0..99), no LF.
/// Throws std::invalid_argument for steps outside 0..9999 or last < first.
std::string scanCommand(int first, int last, int cluster, int chars = 3);
/// Number of values a scan of first..last with `cluster` returns.
int scanValueCount(int first, int last, int cluster);
/// Decodes a complete GD/GS reply: status "00", a 4-char time line and ceil(values*chars/64) data
/// lines holding exactly the expected number of values. Throws ScipError(kStatus) on an error
/// status (naming its meaning), ScipError(kFormat) on a malformed block.
ScanData decodeScanReply(const Reply& reply, int first, int last, int cluster, int chars = 3);

/// Parses the KEY:value data lines of VV/PP/II (sums already removed, ';' optional); lines
/// without ':' are ignored (some firmware sends an extra line break).
std::vector<std::pair<std::string, std::string>> parseKeyValues(const Reply& reply);

/// The meaning of a SCIP 2.0 status code (for messages).
std::string statusMeaning(const std::string& command, const std::string& status);
/// The meaning of a range value below DMIN (an error code, PROTOCOL_FACTS 1.5).
const char* errorCodeMeaning(uint32_t code);

}  // namespace urg
}  // namespace scanstop
