#pragma once
/// The ROS master watchdog's state machine (issue #22 class 5), ROS-free: fed with the result of
/// a periodic check of the master (reachable or not, and the master's process id when known), it
/// says once when the master is lost (naming its URI and how long it has been gone), when it is
/// back, when it has been gone longer than the timeout, and when a *new* master answers on the URI
/// (a restarted roscore: the nodes' topics and services are not registered with it).
///
///   Ok --unreachable--> Lost(since t) --reachable, same master--> Ok
///                          |  \--reachable, another pid--> Restarted (final)
///                          \--now - t >= timeout--> TimedOut (final)
///   Ok --reachable, another pid--> Restarted (final)
///
/// t is the time of the last check that reached the master (the master may have gone right after
/// it), or the time of the first check when none has.

#include <string>

namespace scanstop {

class MasterWatchdog {
 public:
  enum class State { Ok, Lost, TimedOut, Restarted };
  enum class Event { None, Lost, Back, TimedOut, Restarted };

  /// master_uri: named in the messages. timeout_s: how long the master may be gone (finite, > 0;
  /// ConfigError naming `master_timeout_s` otherwise).
  MasterWatchdog(std::string master_uri, double timeout_s);

  /// One check at now_s [s, a monotonic clock]: whether it reached the master and, when it did and
  /// knows it, the master's pid (< 0: unknown, never counts as a restart). Returns the event this
  /// check caused (each happens once; None otherwise); message() then describes it.
  Event update(double now_s, bool reachable, long master_pid = -1);

  State state() const { return state_; }
  /// Seconds the master has been gone at now_s (0 while it is reachable).
  double lostFor(double now_s) const;
  /// The last event's message, e.g. "the ROS master at http://127.0.0.1:11311 is unreachable
  /// (no answer for 1.0 s); ..." (empty before the first event).
  const std::string& message() const { return message_; }
  const std::string& masterUri() const { return uri_; }
  double timeout() const { return timeout_s_; }

 private:
  std::string uri_;
  double timeout_s_;
  State state_ = State::Ok;
  bool seen_ = false;       ///< a check has run
  double last_ok_s_ = 0.0;  ///< the last check that reached the master (or the first check)
  double lost_since_s_ = 0.0;
  long pid_ = -1;  ///< the master's pid when first known
  std::string message_;
};

const char* toString(MasterWatchdog::Event e);

}  // namespace scanstop
