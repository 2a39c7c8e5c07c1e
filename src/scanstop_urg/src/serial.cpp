#include "scanstop_urg/serial.h"

#include "scanstop_common/serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstring>

namespace scanstop {
namespace urg {
namespace {

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

}  // namespace

SerialPort::SerialPort(const std::string& path, int baud) : path_(path) {
  if (!isSupportedBaud(baud))
    throw std::invalid_argument("unsupported baud rate " + std::to_string(baud) + " (" + supportedBauds() + ")");
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) throw ScipError(ScipError::Kind::kDisconnected, "cannot open " + path + ": " + std::strerror(errno));
  if (!configureRawSerial(fd_, baud)) {
    const bool not_tty = errno == ENOTTY;
    const std::string err = std::strerror(errno);
    ::close(fd_);
    fd_ = -1;
    throw ScipError(ScipError::Kind::kDisconnected,
                    not_tty ? path + " is not a serial port: " + err : "cannot configure " + path + ": " + err);
  }
  tcflush(fd_, TCIOFLUSH);
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) ::close(fd_);
}

void SerialPort::write(const std::string& bytes) {
  size_t done = 0;
  const double deadline = now_s() + 2.0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR)
      throw ScipError(ScipError::Kind::kDisconnected, "write to " + path_ + " failed: " + std::strerror(errno));
    if (now_s() > deadline) throw ScipError(ScipError::Kind::kTimeout, "write to " + path_ + " blocked for 2 s");
    pollfd p{fd_, POLLOUT, 0};
    ::poll(&p, 1, 50);
  }
}

size_t SerialPort::read(char* buffer, size_t size, double timeout_s) {
  pollfd p{fd_, POLLIN, 0};
  const int ms = timeout_s <= 0 ? 0 : static_cast<int>(timeout_s * 1000.0 + 0.5);
  const int rc = ::poll(&p, 1, ms);
  if (rc < 0) {
    if (errno == EINTR) return 0;
    throw ScipError(ScipError::Kind::kDisconnected, "poll on " + path_ + " failed: " + std::strerror(errno));
  }
  if (rc == 0) return 0;
  if (p.revents & POLLIN) {
    const ssize_t n = ::read(fd_, buffer, size);
    if (n > 0) return static_cast<size_t>(n);
    if (n == 0 || (errno != EAGAIN && errno != EINTR))
      throw ScipError(ScipError::Kind::kDisconnected, path_ + " was closed (device unplugged?)");
    return 0;
  }
  if (p.revents & (POLLHUP | POLLERR | POLLNVAL))
    throw ScipError(ScipError::Kind::kDisconnected, path_ + " hung up (device unplugged?)");
  return 0;
}

void SerialPort::discardInput() { tcflush(fd_, TCIFLUSH); }

bool SerialPort::alive() {
  pollfd p{fd_, 0, 0};
  if (::poll(&p, 1, 0) < 0) return errno == EINTR;
  return (p.revents & (POLLHUP | POLLERR | POLLNVAL)) == 0;
}

bool LineChannel::readLine(std::string* line, double timeout_s) {
  const double deadline = now_s() + timeout_s;
  char buf[512];
  while (lines_.empty()) {
    const double left = deadline - now_s();
    if (left <= 0) return false;
    const size_t n = stream_.read(buf, sizeof(buf), left);
    if (n > 0) splitter_.feed(buf, n, [this](const std::string& l) { lines_.push_back(l); });
  }
  *line = std::move(lines_.front());
  lines_.pop_front();
  return true;
}

void LineChannel::drain(double quiet_s, double max_s) {
  lines_.clear();
  splitter_.reset();
  stream_.discardInput();
  const double deadline = now_s() + max_s;
  char buf[512];
  while (now_s() < deadline) {
    if (stream_.read(buf, sizeof(buf), quiet_s) == 0) break;
  }
  splitter_.reset();
}

}  // namespace urg
}  // namespace scanstop
