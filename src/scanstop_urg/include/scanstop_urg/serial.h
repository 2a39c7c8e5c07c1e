#pragma once
/// Byte streams to the devices: the interface (so that an in-process emulator can stand in for a
/// device in tests), the POSIX serial port (termios raw 8N1, no flow control) and a line channel
/// that reads LF-terminated lines with deadlines. C++17 and POSIX only.

#include <deque>
#include <memory>
#include <string>

#include "scanstop_urg/scip.h"

namespace scanstop {
namespace urg {

/// A bidirectional byte stream. Errors of the link throw ScipError(kDisconnected).
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  virtual void write(const std::string& bytes) = 0;
  /// Reads up to `size` bytes, waiting at most `timeout_s`; returns 0 on timeout.
  virtual size_t read(char* buffer, size_t size, double timeout_s) = 0;
  /// Discards received but unread bytes (tcflush).
  virtual void discardInput() = 0;
  /// False when the link has hung up (device unplugged, pty closed); does not read.
  virtual bool alive() = 0;
};

/// A serial port in raw 8N1 mode without flow control (cfmakeraw; no ICANON, ECHO, ICRNL, OPOST).
/// Works on ttyACM/ttyUSB devices and on pseudo-terminal slaves.
class SerialPort : public ByteStream {
 public:
  /// Opens and configures `path`; throws ScipError(kDisconnected) naming the path and the reason.
  SerialPort(const std::string& path, int baud);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  void write(const std::string& bytes) override;
  size_t read(char* buffer, size_t size, double timeout_s) override;
  void discardInput() override;
  bool alive() override;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

/// Reads lines from a ByteStream with deadlines.
class LineChannel {
 public:
  explicit LineChannel(ByteStream& stream, size_t max_line = 128) : stream_(stream), splitter_(max_line) {}
  void writeLine(const std::string& line) { stream_.write(line + "\n"); }
  void write(const std::string& bytes) { stream_.write(bytes); }
  /// The next complete line, waiting at most `timeout_s`; false on timeout.
  bool readLine(std::string* line, double timeout_s);
  /// Resynchronisation: discards queued lines, the partial line and everything that arrives until
  /// the link has been quiet for `quiet_s` (at most `max_s`).
  void drain(double quiet_s, double max_s);
  /// Lines dropped because they were longer than the maximum (garbage without LF).
  uint64_t overflows() const { return splitter_.overflows(); }
  ByteStream& stream() { return stream_; }

 private:
  ByteStream& stream_;
  LineSplitter splitter_;
  std::deque<std::string> lines_;
};

}  // namespace urg
}  // namespace scanstop
