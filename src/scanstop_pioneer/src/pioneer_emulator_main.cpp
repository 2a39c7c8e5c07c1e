// pioneer_emulator: a Pioneer 2 DX on a pseudo-terminal. Prints the slave device, keeps an optional
// symlink to it, and takes fault commands line by line from an optional control FIFO.
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

#include "scanstop_pioneer/pty_emulator.h"

namespace {

volatile sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

void usage() {
  std::cerr << "usage: pioneer_emulator [--link PATH] [--control FIFO] [--start-open] [--name NAME]\n"
               "                        [--subclass SUB] [--sip-period S] [--watchdog S] [--seed N]\n"
               "                        [--start-x MM] [--start-y MM]\n"
               "  --link PATH     keep a symlink PATH -> the pty slave (open PATH as the robot's port)\n"
               "  --control FIFO  create FIFO and read fault commands from it, one per line:\n"
               "                  corrupt N | drop N | garbage N | silence S | disconnect S | stall on|off |\n"
               "                  encoder on|off | motors on|off | bump front|rear|off | still_open |\n"
               "                  battery V | status\n"
               "  --start-open    start with a session left open by an earlier client (SIPs streaming)\n"
               "  --start-x/-y MM odometry counters at OPEN (e.g. 27400 to cross the 15-bit wrap soon)\n";
}

double number(const char* text, const char* option) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (*end != '\0' || !(v >= 0.0)) {
    std::cerr << "pioneer_emulator: " << option << " needs a non-negative number, got '" << text << "'\n";
    std::exit(2);
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  scanstop::pioneer::EmulatorConfig config;
  std::string link, control;
  bool start_open = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--link" && has_value) {
      link = argv[++i];
    } else if (a == "--control" && has_value) {
      control = argv[++i];
    } else if (a == "--start-open") {
      start_open = true;
    } else if (a == "--name" && has_value) {
      config.identity.name = argv[++i];
    } else if (a == "--subclass" && has_value) {
      config.identity.subclass = argv[++i];
    } else if (a == "--sip-period" && has_value) {
      config.sip_period_s = number(argv[++i], "--sip-period");
    } else if (a == "--watchdog" && has_value) {
      config.watchdog_s = number(argv[++i], "--watchdog");
    } else if (a == "--start-x" && has_value) {
      config.start_x_mm = number(argv[++i], "--start-x");
    } else if (a == "--start-y" && has_value) {
      config.start_y_mm = number(argv[++i], "--start-y");
    } else if (a == "--seed" && has_value) {
      config.seed = static_cast<uint32_t>(number(argv[++i], "--seed"));
    } else if (a == "-h" || a == "--help") {
      usage();
      return 0;
    } else if (a.rfind("__", 0) == 0) {
      // roslaunch appends __name:= and __log:= arguments.
    } else {
      std::cerr << "pioneer_emulator: unknown or incomplete argument '" << a << "'\n";
      usage();
      return 2;
    }
  }
  if (config.sip_period_s < 0.01 || config.sip_period_s > 1.0) {
    std::cerr << "pioneer_emulator: --sip-period " << config.sip_period_s << " must be within [0.01, 1] s\n";
    return 2;
  }
  signal(SIGINT, onSignal);
  signal(SIGTERM, onSignal);

  int fifo = -1;
  if (!control.empty()) {
    ::unlink(control.c_str());
    if (::mkfifo(control.c_str(), 0600) != 0) {
      std::cerr << "pioneer_emulator: cannot create control FIFO " << control << ": " << std::strerror(errno) << "\n";
      return 1;
    }
    // O_RDWR: the FIFO never reports end-of-file when a writer goes away.
    fifo = ::open(control.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fifo < 0) {
      std::cerr << "pioneer_emulator: cannot open control FIFO " << control << ": " << std::strerror(errno) << "\n";
      return 1;
    }
  }
  try {
    scanstop::pioneer::PtyEmulator emulator(config, link);
    emulator.start();
    if (start_open) emulator.command("still_open");
    std::cout << "pioneer_emulator: robot '" << config.identity.name << "' (" << config.identity.subclass << ") on "
              << emulator.slavePath() << (link.empty() ? "" : " (link " + link + ")")
              << (start_open ? ", session left open" : "") << std::endl;
    std::string pending;
    while (!g_stop) {
      if (fifo < 0) {
        usleep(100000);
        continue;
      }
      pollfd p{fifo, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buf[256];
      const ssize_t n = ::read(fifo, buf, sizeof(buf));
      if (n <= 0) continue;
      pending.append(buf, static_cast<size_t>(n));
      size_t nl;
      while ((nl = pending.find('\n')) != std::string::npos) {
        const std::string line = pending.substr(0, nl);
        pending.erase(0, nl + 1);
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        try {
          std::cout << "pioneer_emulator: " << emulator.command(line) << std::endl;
        } catch (const std::exception& e) {
          std::cout << "pioneer_emulator: error: " << e.what() << std::endl;
        }
      }
    }
    emulator.stop();
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  if (fifo >= 0) {
    ::close(fifo);
    ::unlink(control.c_str());
  }
  return 0;
}
