// urg_emulator: a Hokuyo URG-04LX (SCIP 2.0, boots in SCIP 1.1) and the stepper rotation controller
// on two pseudo-terminals, answering from a box room; faults on request through a control FIFO.
// Usage: see usage() below and the package README.
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/serial.h"
#include "scanstop_urg/emulator.h"
#include "scanstop_urg/scip.h"

using namespace scanstop::urg;

namespace {

volatile sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

void usage() {
  std::fprintf(stderr,
               "usage: urg_emulator [options]\n"
               "  --link PATH           symlink to the URG pty slave (e.g. /tmp/urg)\n"
               "  --platform-link PATH  symlink to the stepper controller pty slave\n"
               "  --control PATH        FIFO for fault commands (created when missing)\n"
               "  --scan-period S       time per GD scan [s] (default 0.1 = 600 rpm)\n"
               "  --room XMIN,XMAX,YMIN,YMAX,ZMAX   box room [m] (default -3,3,-2.5,2.5,2.5)\n"
               "  --robot X,Y,YAW       base_link in the room [m, m, rad] (default 0.4,-0.3,0.3)\n"
               "  --height H            scanner rotation centre above the floor [m] (default 0.45)\n"
               "  --x-offset X          rotation axis ahead of base_link [m] (default 0)\n"
               "  --mount-offset M      optical centre off the axis [m] (default 0)\n"
               "  --no-dark-patch       no low-reflectance patch on the +x wall\n"
               "  --boot-scip2          start in SCIP 2.0 (default: SCIP 1.1 like a powered-up URG-04LX)\n"
               "  --stale-stream        start in SCIP 2.0 with an endless MD stream running, as a crashed\n"
               "                        client leaves it\n"
               "control commands (one per line): corrupt N | drop N [BYTES] | truncate N | garbage |\n"
               "  silence SECONDS | disconnect SECONDS | powercycle | stall N | laser_fault 0|1 | quit\n");
}

std::vector<double> parseList(const std::string& text, size_t n, const char* what) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0') {
      std::fprintf(stderr, "urg_emulator: %s: '%s' is not a number\n", what, item.c_str());
      std::exit(2);
    }
    v.push_back(x);
  }
  if (v.size() != n) {
    std::fprintf(stderr, "urg_emulator: %s needs %zu comma-separated numbers, got '%s'\n", what, n, text.c_str());
    std::exit(2);
  }
  return v;
}

double parseNumber(const std::string& text, const char* what) { return parseList(text, 1, what)[0]; }

/// One pseudo-terminal: the master side is the device; the slave (symlinked) is the port.
struct Pty {
  std::string name, link;
  int master = -1, slave_keep = -1;
  std::string slave_path;
  LineSplitter splitter{256};

  bool open() {
    master = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) {
      std::fprintf(stderr, "urg_emulator: posix_openpt for %s failed: %s\n", name.c_str(), std::strerror(errno));
      return false;
    }
    slave_path = ptsname(master);
    // Keep a slave descriptor open ourselves, so the master does not hang up between clients;
    // put the slave into raw mode (a fresh pty echoes and maps LF to CRLF).
    slave_keep = ::open(slave_path.c_str(), O_RDWR | O_NOCTTY);
    if (slave_keep >= 0) scanstop::configureRawSerial(slave_keep, 0);
    if (!link.empty()) {
      const std::string tmp = link + ".tmp";
      ::unlink(tmp.c_str());
      if (::symlink(slave_path.c_str(), tmp.c_str()) != 0 || ::rename(tmp.c_str(), link.c_str()) != 0) {
        std::fprintf(stderr, "urg_emulator: cannot link %s -> %s: %s\n", link.c_str(), slave_path.c_str(),
                     std::strerror(errno));
        return false;
      }
    }
    splitter.reset();
    std::printf("urg_emulator: %s on %s%s%s\n", name.c_str(), slave_path.c_str(), link.empty() ? "" : " linked from ",
                link.c_str());
    std::fflush(stdout);
    return true;
  }
  void close() {
    if (!link.empty()) ::unlink(link.c_str());
    if (master >= 0) ::close(master);
    if (slave_keep >= 0) ::close(slave_keep);
    master = slave_keep = -1;
  }
  void send(const std::string& bytes) {
    size_t done = 0;
    const double deadline = now_s() + 1.0;
    while (master >= 0 && done < bytes.size() && now_s() < deadline) {
      const ssize_t n = ::write(master, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<size_t>(n);
      } else {
        pollfd p{master, POLLOUT, 0};
        ::poll(&p, 1, 10);
      }
    }
  }
};

struct Pending {
  double due;
  std::string bytes;
};

}  // namespace

int main(int argc, char** argv) {
  BoxRoomScene scene;
  Pty urg_pty, platform_pty;
  urg_pty.name = "URG";
  platform_pty.name = "platform";
  std::string control_path;
  double scan_period = 0.1;
  bool boot_scip2 = false, stale_stream = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "urg_emulator: %s needs a value\n", a.c_str());
        usage();
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--link")
      urg_pty.link = next();
    else if (a == "--platform-link")
      platform_pty.link = next();
    else if (a == "--control")
      control_path = next();
    else if (a == "--scan-period")
      scan_period = parseNumber(next(), "--scan-period");
    else if (a == "--room") {
      const auto v = parseList(next(), 5, "--room");
      scene.x_min = v[0], scene.x_max = v[1], scene.y_min = v[2], scene.y_max = v[3], scene.z_max = v[4];
    } else if (a == "--robot") {
      const auto v = parseList(next(), 3, "--robot");
      scene.robot_x = v[0], scene.robot_y = v[1], scene.robot_yaw = v[2];
    } else if (a == "--height")
      scene.scanner_height = parseNumber(next(), "--height");
    else if (a == "--x-offset")
      scene.scanner_x_offset = parseNumber(next(), "--x-offset");
    else if (a == "--mount-offset")
      scene.mount_offset = parseNumber(next(), "--mount-offset");
    else if (a == "--no-dark-patch")
      scene.dark_patch = false;
    else if (a == "--boot-scip2")
      boot_scip2 = true;
    else if (a == "--stale-stream")
      stale_stream = true;
    else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else if (a.rfind("__", 0) == 0) {
      continue;  // roslaunch's __name:= / __log:= arguments
    } else {
      std::fprintf(stderr, "urg_emulator: unknown argument '%s'\n", a.c_str());
      usage();
      return 2;
    }
  }
  try {
    scene.validate();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "urg_emulator: %s\n", e.what());
    return 2;
  }
  if (!(scan_period >= 0.0 && scan_period <= 10.0)) {
    std::fprintf(stderr, "urg_emulator: --scan-period must be in [0, 10] s\n");
    return 2;
  }
  signal(SIGINT, onSignal);
  signal(SIGTERM, onSignal);
  signal(SIGPIPE, SIG_IGN);

  StepperEmulator stepper;
  UrgEmulator urg([&](int step) { return scene.value(stepper.angle(), step); });
  urg.setScanPeriod(scan_period);
  if (boot_scip2 || stale_stream) urg.handleLine("SCIP2.0");
  if (stale_stream) urg.handleLine("MD0044072501000;crashed");  // nobody reads the acknowledgement
  FaultInjector faults(20261129);
  std::mt19937 rng(5);

  int control = -1;
  bool made_fifo = false;
  LineSplitter control_splitter(256);
  if (!control_path.empty()) {
    struct stat st {};
    if (::stat(control_path.c_str(), &st) == 0) {
      if (!S_ISFIFO(st.st_mode)) {
        std::fprintf(stderr, "urg_emulator: --control %s exists and is not a FIFO\n", control_path.c_str());
        return 2;
      }
    } else if (::mkfifo(control_path.c_str(), 0600) == 0) {
      made_fifo = true;
    } else {
      std::fprintf(stderr, "urg_emulator: cannot create the control FIFO %s: %s\n", control_path.c_str(),
                   std::strerror(errno));
      return 1;
    }
    control = ::open(control_path.c_str(), O_RDWR | O_NONBLOCK);  // O_RDWR: never sees EOF
    if (control < 0) {
      std::fprintf(stderr, "urg_emulator: cannot open %s: %s\n", control_path.c_str(), std::strerror(errno));
      return 1;
    }
  }
  if (!urg_pty.open() || !platform_pty.open()) return 1;

  std::deque<Pending> urg_out;
  double last_due = 0.0, silence_until = 0.0, reconnect_at = 0.0, last_tick = now_s(), next_stream = 0.0;
  bool disconnected = false, quit = false;

  auto handleControl = [&](const std::string& line) {
    std::istringstream in(line);
    std::string cmd;
    in >> cmd;
    double x = 1.0, y = 3.0;
    in >> x;
    if (!in) x = 1.0;
    in >> y;
    if (!in) y = 3.0;
    if (cmd == "corrupt") {
      faults.corruptChecksums(static_cast<int>(x));
    } else if (cmd == "drop") {
      faults.dropBytes(static_cast<int>(x), static_cast<int>(y));
    } else if (cmd == "truncate") {
      faults.truncate(static_cast<int>(x));
    } else if (cmd == "garbage") {
      std::string g;
      std::uniform_int_distribution<int> c(0x20, 0x7E);
      for (int k = 0; k < 300; ++k) g.push_back(static_cast<char>(c(rng)));
      g += "\n0?X0CB\n00P\n\n";  // then fragments of a reply
      urg_pty.send(g);
    } else if (cmd == "silence") {
      silence_until = now_s() + x;
      urg_out.clear();
    } else if (cmd == "disconnect") {
      urg_pty.close();
      platform_pty.close();
      urg_out.clear();
      disconnected = true;
      reconnect_at = now_s() + x;
    } else if (cmd == "powercycle") {
      urg.powerCycle();
      urg_out.clear();
    } else if (cmd == "stall") {
      stepper.injectStall(static_cast<int>(x));
    } else if (cmd == "laser_fault") {
      urg.setLaserFault(x != 0.0);
    } else if (cmd == "quit") {
      quit = true;
    } else if (!cmd.empty()) {
      std::printf("urg_emulator: unknown control command '%s'\n", line.c_str());
      std::fflush(stdout);
      return;
    }
    if (!cmd.empty()) {
      std::printf("urg_emulator: fault '%s'\n", line.c_str());
      std::fflush(stdout);
    }
  };

  char buf[4096];
  while (!g_stop && !quit) {
    const double t = now_s();
    urg.advance(t - last_tick);
    last_tick = t;
    if (disconnected && t >= reconnect_at) {
      if (!urg_pty.open() || !platform_pty.open()) return 1;
      disconnected = false;
    }
    // A running MD stream sends a scan every scan period.
    if (urg.streaming() && !disconnected && t >= next_stream && t >= silence_until) {
      const UrgEmulator::Response r = urg.nextStreamScan();
      const double due = std::max(t, last_due);
      last_due = due;
      urg_out.push_back({due, r.bytes});
      next_stream = t + std::max(r.delay_s, 0.001);
    }
    // Send the replies that are due.
    while (!urg_out.empty() && urg_out.front().due <= t) {
      urg_pty.send(urg_out.front().bytes);
      urg_out.pop_front();
    }
    std::vector<pollfd> fds;
    if (urg_pty.master >= 0) fds.push_back({urg_pty.master, POLLIN, 0});
    if (platform_pty.master >= 0) fds.push_back({platform_pty.master, POLLIN, 0});
    if (control >= 0) fds.push_back({control, POLLIN, 0});
    double wait = 0.05;
    if (!urg_out.empty()) wait = std::min(wait, std::max(0.0, urg_out.front().due - t));
    if (urg.streaming()) wait = std::min(wait, std::max(0.0, next_stream - t));
    ::poll(fds.data(), fds.size(), static_cast<int>(wait * 1000.0));
    for (const pollfd& p : fds) {
      if (!(p.revents & POLLIN)) continue;
      const ssize_t n = ::read(p.fd, buf, sizeof(buf));
      if (n <= 0) continue;
      if (p.fd == control) {
        control_splitter.feed(buf, static_cast<size_t>(n), handleControl);
      } else if (p.fd == platform_pty.master) {
        platform_pty.splitter.feed(buf, static_cast<size_t>(n),
                                   [&](const std::string& line) { platform_pty.send(stepper.handleLine(line)); });
      } else if (p.fd == urg_pty.master) {
        urg_pty.splitter.feed(buf, static_cast<size_t>(n), [&](const std::string& line) {
          if (now_s() < silence_until) return;  // silent: commands are lost
          UrgEmulator::Response r = urg.handleLine(line);
          if (r.bytes.empty()) return;
          if (faults.apply(r.bytes)) {
            std::printf("urg_emulator: fault applied to the reply to '%s'\n", line.c_str());
            std::fflush(stdout);
          }
          const double due = std::max(now_s(), last_due) + r.delay_s;
          last_due = due;
          urg_out.push_back({due, r.bytes});
        });
      }
    }
  }
  urg_pty.close();
  platform_pty.close();
  if (control >= 0) ::close(control);
  if (made_fifo) ::unlink(control_path.c_str());
  return 0;
}
