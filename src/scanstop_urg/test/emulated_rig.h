#pragma once
// In-process stand-ins for the two serial devices: byte streams that feed the URG and stepper
// emulators directly (no pty), with the same fault injection as urg_emulator plus silence and
// unplugging. A read with nothing queued waits for its timeout (short in the tests).
#include <chrono>
#include <memory>
#include <thread>

#include "scanstop_urg/driver.h"
#include "scanstop_urg/emulator.h"

namespace scanstop {
namespace urg {
namespace testing {

struct Rig {
  BoxRoomScene scene;
  StepperEmulator stepper;
  UrgEmulator urg{[this](int step) { return scene.value(stepper.angle(), step); }};
  FaultInjector faults{11};
  int silent_replies = 0;  ///< the URG ignores this many commands
  bool unplugged = false;  ///< both streams fail; new ones cannot be opened
  int opens = 0;
  std::string noise_before_next_reply;  ///< bytes sent before the next URG reply (stale lines, garbage)
};

class EmulatedStream : public ByteStream {
 public:
  EmulatedStream(Rig& rig, bool is_urg) : rig_(rig), is_urg_(is_urg) {}
  void write(const std::string& bytes) override {
    if (rig_.unplugged) throw ScipError(ScipError::Kind::kDisconnected, "emulated device unplugged");
    splitter_.feed(bytes.data(), bytes.size(), [this](const std::string& line) {
      if (!is_urg_) {
        out_ += rig_.stepper.handleLine(line);
        return;
      }
      // A running MD stream (left by a crashed client) sends a scan before each reply.
      const std::string stream = rig_.urg.streaming() ? rig_.urg.nextStreamScan().bytes : "";
      UrgEmulator::Response r = rig_.urg.handleLine(line);
      rig_.urg.advance(r.delay_s);
      if (rig_.silent_replies > 0) {
        --rig_.silent_replies;
        return;
      }
      rig_.faults.apply(r.bytes);
      out_ += stream + rig_.noise_before_next_reply + r.bytes;
      rig_.noise_before_next_reply.clear();
    });
  }
  size_t read(char* buffer, size_t size, double timeout_s) override {
    if (rig_.unplugged) throw ScipError(ScipError::Kind::kDisconnected, "emulated device unplugged");
    if (out_.empty()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(timeout_s));
      return 0;
    }
    // Deliver in small pieces, as a serial port does.
    const size_t n = std::min({size, out_.size(), static_cast<size_t>(100)});
    out_.copy(buffer, n);
    out_.erase(0, n);
    return n;
  }
  void discardInput() override { out_.clear(); }
  bool alive() override { return !rig_.unplugged; }

 private:
  Rig& rig_;
  bool is_urg_;
  LineSplitter splitter_;
  std::string out_;
};

inline StreamFactory rigFactory(Rig& rig) {
  return [&rig](const std::string& path, int) -> std::unique_ptr<ByteStream> {
    if (rig.unplugged) throw ScipError(ScipError::Kind::kDisconnected, "cannot open " + path + ": no such device");
    ++rig.opens;
    return std::make_unique<EmulatedStream>(rig, path.find("platform") == std::string::npos);
  };
}

/// Fast settings for in-process tests.
inline DriverConfig fastConfig() {
  DriverConfig c;
  c.urg_port = "emulated-urg";
  c.platform_port = "emulated-platform";
  c.urg.reply_timeout_s = 0.05;
  c.urg.scan_timeout_s = 0.05;
  c.stepper.reply_timeout_s = 0.05;
  c.stepper.home_timeout_s = 0.05;
  c.scanner.settle_time_s = 0.0;
  return c;
}

}  // namespace testing
}  // namespace urg
}  // namespace scanstop
