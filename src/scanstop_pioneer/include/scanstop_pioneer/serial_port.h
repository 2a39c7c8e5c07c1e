#pragma once
/// A raw 8N1 serial port (termios) behind a small byte-stream interface, so the protocol client
/// can run on a real port, a pseudo-terminal or a test double.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace scanstop {
namespace pioneer {

/// The link broke (device gone, hang-up, I/O error); what() names the device and the cause.
class LinkError : public std::runtime_error {
 public:
  explicit LinkError(const std::string& message) : std::runtime_error(message) {}
};

/// A bidirectional byte stream.
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  /// Reads up to n bytes, waiting at most timeout_s; returns 0 on timeout. Throws LinkError.
  virtual size_t read(uint8_t* data, size_t n, double timeout_s) = 0;
  /// Writes all bytes (bounded wait); throws LinkError.
  virtual void write(const uint8_t* data, size_t n) = 0;
  /// Discards bytes received but not read (tcflush).
  virtual void flushInput() = 0;
};

/// A serial device in raw mode (cfmakeraw: 8N1, no flow control, no echo or line processing).
class SerialPort : public ByteStream {
 public:
  SerialPort() = default;
  ~SerialPort() override { close(); }
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens `path` at `baud` (9600, 19200, 38400, 57600 or 115200); throws LinkError naming the
  /// path and the system error.
  void open(const std::string& path, int baud);
  void close();
  bool isOpen() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

  size_t read(uint8_t* data, size_t n, double timeout_s) override;
  void write(const uint8_t* data, size_t n) override;
  void flushInput() override;

 private:
  int fd_ = -1;
  std::string path_;
};

}  // namespace pioneer
}  // namespace scanstop
