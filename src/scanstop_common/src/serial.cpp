#include "scanstop_common/serial.h"

#include <errno.h>
#include <termios.h>

namespace scanstop {
namespace {

struct Rate {
  int baud;
  speed_t speed;
};
constexpr Rate kRates[] = {{9600, B9600},     {19200, B19200},   {38400, B38400},   {57600, B57600},
                           {115200, B115200}, {230400, B230400}, {500000, B500000}, {1000000, B1000000}};

}  // namespace

bool isSupportedBaud(int baud) {
  for (const Rate& r : kRates)
    if (r.baud == baud) return true;
  return false;
}

std::string supportedBauds() {
  std::string out;
  for (const Rate& r : kRates) out += (out.empty() ? "" : ", ") + std::to_string(r.baud);
  return out;
}

bool configureRawSerial(int fd, int baud) {
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) return false;
  cfmakeraw(&tio);  // 8 bits, no parity, no ICANON/ECHO/ICRNL/OPOST
  tio.c_cflag &= ~(CSTOPB | CRTSCTS | PARENB);
  tio.c_cflag |= CLOCAL | CREAD | CS8;
  tio.c_iflag &= ~(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (baud != 0) {
    const Rate* rate = nullptr;
    for (const Rate& r : kRates)
      if (r.baud == baud) rate = &r;
    if (!rate) {
      errno = EINVAL;
      return false;
    }
    cfsetispeed(&tio, rate->speed);
    cfsetospeed(&tio, rate->speed);
  }
  return tcsetattr(fd, TCSANOW, &tio) == 0;
}

}  // namespace scanstop
