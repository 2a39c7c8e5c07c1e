#pragma once
/// The rotation platform that turns the URG's scan plane about the vertical axis, behind an
/// interface so that another drive (a servo, say) can replace the stepper controller.
///
/// Stepper controller protocol (ours; the thesis' board is custom). Serial, raw 8N1, ASCII lines
/// ending in LF. Every line in both directions ends with one sum character computed as in SCIP
/// (sum of the preceding bytes & 0x3F, + 0x30). The host sends `CC[params]S\n`; the controller
/// answers exactly one line `CCss[values]S\n` where `ss` is a 2-digit status (see the constants).
///
///   | Command   | Meaning                                               | Reply values        |
///   |-----------|-------------------------------------------------------|---------------------|
///   | `SCnnnn`  | set the step count: positions per half turn, 1..4000  | none                |
///   |           | (the position becomes unknown: home next)             |                     |
///   | `HM`      | home: turn to the index switch, position 0            | none                |
///   | `ST`      | step: advance one position (pi / count)               | `pppp` new position |
///   | `SS`      | status                                                | `ppppnnnnhee`: position, count, homed 0/1,
///   latched error | | `ER`      | read and clear the latched error                      | `ee`                |
///
/// A failed command latches its status as the error. A stall loses the position (homed = 0).
/// The reply to a line with a bad sum is `XX05S`. Position k means the angle k * pi / count.

#include <memory>
#include <stdexcept>
#include <string>

#include "scanstop_urg/serial.h"

namespace scanstop {
namespace urg {

/// A platform failure; `transient` when retrying the same command may help.
class PlatformError : public std::runtime_error {
 public:
  PlatformError(const std::string& message, bool transient, bool link_lost = false)
      : std::runtime_error(message), transient_(transient), link_lost_(link_lost) {}
  bool transient() const { return transient_; }
  /// The serial link failed or the controller stopped answering: reconnect.
  bool linkLost() const { return link_lost_; }

 private:
  bool transient_, link_lost_;
};

namespace stepper {
constexpr int kOk = 0, kNotHomed = 1, kBadParameter = 2, kStall = 3, kEndOfTravel = 4, kBadSum = 5, kUnknownCommand = 6,
              kNotConfigured = 7;
constexpr int kMaxCount = 4000;
/// The meaning of a status code.
const char* statusMeaning(int status);
/// A host command line with sum and LF.
std::string formatCommand(const std::string& cmd, const std::string& params = "");
/// A controller reply line with sum and LF.
std::string formatReply(const std::string& cmd, int status, const std::string& values);
struct Reply {
  std::string cmd;
  int status = 0;
  std::string values;
};
/// Parses a reply line (without LF); throws PlatformError (transient) on a bad sum or format.
Reply parseReply(const std::string& line);
}  // namespace stepper

/// Where the platform stands.
struct PlatformStatus {
  int position = 0;  ///< plane index
  int count = 0;     ///< positions per half turn
  bool homed = false;
  int error = 0;  ///< latched error code (0 = none)
};

/// A drive that turns the scan plane in `planes` equal steps over half a turn.
class RotationPlatform {
 public:
  virtual ~RotationPlatform() = default;
  /// Sets the resolution to `planes` per half turn and moves to plane 0 (angle 0).
  virtual void prepare(int planes) = 0;
  /// Moves to the next plane; returns the plane index the drive reports.
  virtual int advance() = 0;
  virtual PlatformStatus status() = 0;
  /// Turns to the rest position after a scan (plane 0).
  virtual void park() = 0;
  virtual std::string describe() const = 0;
};

struct StepperConfig {
  double reply_timeout_s = 1.0;  ///< for SC, ST, SS, ER [s]
  double home_timeout_s = 10.0;  ///< for HM (the platform may turn half a turn) [s]
  int retries = 2;               ///< re-sends of a command after a bad sum or a timeout
};

/// The stepper controller over a line channel.
class StepperPlatform : public RotationPlatform {
 public:
  StepperPlatform(ByteStream& stream, const StepperConfig& config);
  void prepare(int planes) override;
  int advance() override;
  PlatformStatus status() override;
  void park() override;
  std::string describe() const override { return "stepper controller"; }

 private:
  /// Sends one command and returns its successful reply; throws PlatformError.
  stepper::Reply transact(const std::string& cmd, const std::string& params, double timeout_s);
  LineChannel channel_;
  StepperConfig config_;
};

}  // namespace urg
}  // namespace scanstop
