#include "scanstop_pioneer/pty_emulator.h"

#include "scanstop_common/serial.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "scanstop_pioneer/serial_port.h"

namespace scanstop {
namespace pioneer {
namespace {

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::runtime_error sysError(const std::string& what) {
  return std::runtime_error("pioneer emulator: " + what + ": " + std::strerror(errno));
}

}  // namespace

PtyEmulator::PtyEmulator(const EmulatorConfig& config, const std::string& link_path)
    : emulator_(config), link_path_(link_path) {}

PtyEmulator::~PtyEmulator() { stop(); }

double PtyEmulator::now() const { return steadySeconds() - t0_; }

std::string PtyEmulator::slavePath() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return slave_path_;
}

std::string PtyEmulator::devicePath() const {
  if (!link_path_.empty()) return link_path_;
  return slavePath();
}

void PtyEmulator::openPty() {
  // Called with mutex_ held.
  const int master = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master < 0) throw sysError("posix_openpt");
  if (grantpt(master) != 0 || unlockpt(master) != 0) {
    ::close(master);
    throw sysError("grantpt/unlockpt");
  }
  char name[128];
  if (ptsname_r(master, name, sizeof(name)) != 0) {
    ::close(master);
    throw sysError("ptsname_r");
  }
  // Keep one slave descriptor open: the master then never reads EIO while no client is attached,
  // and the slave's termios (raw: no echo, no CRLF mapping) stay as set here.
  const int slave = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave < 0 || !configureRawSerial(slave, 0)) {
    if (slave >= 0) ::close(slave);
    ::close(master);
    throw sysError(std::string("raw mode on ") + name);
  }
  fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK);
  master_ = master;
  slave_keep_ = slave;
  slave_path_ = name;
  if (!link_path_.empty()) {
    const std::string tmp = link_path_ + ".tmp";
    ::unlink(tmp.c_str());
    if (::symlink(name, tmp.c_str()) != 0 || ::rename(tmp.c_str(), link_path_.c_str()) != 0)
      throw sysError("symlink " + link_path_ + " -> " + name);
  }
}

void PtyEmulator::closePty() {
  // Called with mutex_ held.
  if (!link_path_.empty()) ::unlink(link_path_.c_str());
  if (slave_keep_ >= 0) ::close(slave_keep_);
  if (master_ >= 0) ::close(master_);
  slave_keep_ = master_ = -1;
  slave_path_.clear();
}

void PtyEmulator::start() {
  if (running_) return;
  t0_ = steadySeconds();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    openPty();
  }
  running_ = true;
  thread_ = std::thread(&PtyEmulator::loop, this);
}

void PtyEmulator::stop() {
  if (running_.exchange(false) && thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(mutex_);
  closePty();
}

std::string PtyEmulator::command(const std::string& line) {
  std::istringstream in(line);
  std::string name;
  double seconds = -1.0;
  in >> name;
  std::lock_guard<std::mutex> lock(mutex_);
  if (name == "disconnect") {
    if (!(in >> seconds) || seconds < 0.0 || seconds > 3600.0)
      throw std::invalid_argument("emulator command '" + line + "': argument must be seconds in [0, 3600]");
    closePty();
    reconnect_at_ = now() + seconds;
    return "ok " + line;
  }
  return emulator_.command(line, now());
}

void PtyEmulator::loop() {
  uint8_t buf[512];
  while (running_) {
    int master = -1;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (master_ < 0 && reconnect_at_ >= 0.0 && now() >= reconnect_at_) {
        try {
          openPty();
          reconnect_at_ = -1.0;
        } catch (const std::exception&) {
          reconnect_at_ = now() + 0.5;
        }
      }
      master = master_;
    }
    if (master >= 0) {
      pollfd p{master, POLLIN, 0};
      ::poll(&p, 1, 10);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const double t = now();
    if (master_ >= 0) {
      for (;;) {
        const ssize_t n = ::read(master_, buf, sizeof(buf));
        if (n <= 0) break;
        emulator_.receive(buf, static_cast<size_t>(n), t);
      }
    }
    emulator_.advance(t);
    const std::vector<uint8_t> out = emulator_.takeOutput();
    if (master_ >= 0 && !out.empty()) {
      // A full input queue on the client side (nobody reading) drops the rest, like a real line.
      size_t done = 0;
      while (done < out.size()) {
        const ssize_t w = ::write(master_, out.data() + done, out.size() - done);
        if (w <= 0) break;
        done += static_cast<size_t>(w);
      }
    }
  }
}

}  // namespace pioneer
}  // namespace scanstop
