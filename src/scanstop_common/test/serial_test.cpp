// Raw serial setup on a pseudo-terminal: the settings the drivers rely on, and clear failures.
#include <errno.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include "scanstop_common/serial.h"

namespace scanstop {
namespace {

TEST(Serial, ConfiguresARaw8N1LineAtTheRate) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  ASSERT_GE(master, 0);
  ASSERT_EQ(grantpt(master), 0);
  ASSERT_EQ(unlockpt(master), 0);
  const int slave = ::open(ptsname(master), O_RDWR | O_NOCTTY);
  ASSERT_GE(slave, 0);
  ASSERT_TRUE(configureRawSerial(slave, 115200));
  termios tio{};
  ASSERT_EQ(tcgetattr(slave, &tio), 0);
  EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B115200));
  EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(tio.c_cflag & (PARENB | CSTOPB | CRTSCTS), 0u);
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO), 0u);
  EXPECT_EQ(tio.c_iflag & (IXON | IXOFF | ICRNL), 0u);
  EXPECT_EQ(tio.c_cc[VMIN], 0);
  // Bytes pass unchanged (no CR/LF translation, no echo).
  const char out[] = "A\r\n\x11\x00";
  ASSERT_EQ(::write(master, out, 5), 5);
  usleep(20000);
  char in[8] = {};
  EXPECT_EQ(::read(slave, in, sizeof in), 5);
  EXPECT_EQ(std::string(in, 5), std::string(out, 5));
  // baud 0 keeps the rate.
  ASSERT_TRUE(configureRawSerial(slave, 0));
  ASSERT_EQ(tcgetattr(slave, &tio), 0);
  EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B115200));
  // An unsupported rate fails with EINVAL and leaves the line alone.
  EXPECT_FALSE(configureRawSerial(slave, 12345));
  EXPECT_EQ(errno, EINVAL);
  ::close(slave);
  ::close(master);
}

TEST(Serial, FailsOnSomethingThatIsNotATerminal) {
  const int fd = ::open("/dev/null", O_RDWR);
  ASSERT_GE(fd, 0);
  EXPECT_FALSE(configureRawSerial(fd, 19200));
  EXPECT_EQ(errno, ENOTTY);
  ::close(fd);
}

TEST(Serial, SupportedRates) {
  EXPECT_TRUE(isSupportedBaud(9600));
  EXPECT_TRUE(isSupportedBaud(1000000));
  EXPECT_FALSE(isSupportedBaud(12345));
  EXPECT_EQ(supportedBauds().rfind("9600, 19200", 0), 0u);
}

}  // namespace
}  // namespace scanstop
