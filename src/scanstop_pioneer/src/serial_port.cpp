#include "scanstop_pioneer/serial_port.h"

#include "scanstop_common/serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cmath>
#include <cstring>

namespace scanstop {
namespace pioneer {
namespace {

std::string sysError(const std::string& what, const std::string& path) {
  return path + ": " + what + ": " + std::strerror(errno);
}

}  // namespace

void SerialPort::open(const std::string& path, int baud) {
  close();
  if (!isSupportedBaud(baud))
    throw LinkError(path + ": baud rate " + std::to_string(baud) + " is not one of " + supportedBauds());
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw LinkError(sysError("cannot open", path));
  if (!configureRawSerial(fd, baud)) {
    const std::string msg = sysError(errno == ENOTTY ? "not a terminal" : "cannot set raw mode", path);
    ::close(fd);
    throw LinkError(msg);
  }
  tcflush(fd, TCIOFLUSH);
  fd_ = fd;
  path_ = path;
}

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

size_t SerialPort::read(uint8_t* data, size_t n, double timeout_s) {
  if (fd_ < 0) throw LinkError(path_ + ": port is not open");
  pollfd p{fd_, POLLIN, 0};
  const int ms = timeout_s <= 0.0 ? 0 : static_cast<int>(std::ceil(timeout_s * 1000.0));
  const int r = ::poll(&p, 1, ms);
  if (r < 0) {
    if (errno == EINTR) return 0;
    throw LinkError(sysError("poll failed", path_));
  }
  if (r == 0) return 0;
  if (p.revents & POLLIN) {
    const ssize_t got = ::read(fd_, data, n);
    if (got > 0) return static_cast<size_t>(got);
    if (got < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
    if (got == 0) throw LinkError(path_ + ": device closed (end of file)");
    throw LinkError(sysError("read failed", path_));
  }
  if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) throw LinkError(path_ + ": device hung up");
  return 0;
}

void SerialPort::write(const uint8_t* data, size_t n) {
  if (fd_ < 0) throw LinkError(path_ + ": port is not open");
  size_t done = 0;
  int waits = 0;
  while (done < n) {
    const ssize_t w = ::write(fd_, data + done, n - done);
    if (w > 0) {
      done += static_cast<size_t>(w);
      continue;
    }
    if (w < 0 && errno != EAGAIN && errno != EINTR) throw LinkError(sysError("write failed", path_));
    pollfd p{fd_, POLLOUT, 0};
    if (++waits > 20 || ::poll(&p, 1, 50) < 0 || (p.revents & (POLLHUP | POLLERR)))
      throw LinkError(path_ + ": cannot write (output blocked or device hung up)");
  }
}

void SerialPort::flushInput() {
  if (fd_ >= 0) tcflush(fd_, TCIFLUSH);
}

}  // namespace pioneer
}  // namespace scanstop
