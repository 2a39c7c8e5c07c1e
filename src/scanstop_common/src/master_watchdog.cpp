#include "scanstop_common/master_watchdog.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "scanstop_common/error.h"

namespace scanstop {
namespace {

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f s", s);
  return buf;
}

}  // namespace

MasterWatchdog::MasterWatchdog(std::string master_uri, double timeout_s)
    : uri_(std::move(master_uri)), timeout_s_(timeout_s) {
  if (!std::isfinite(timeout_s) || timeout_s <= 0.0 || timeout_s > 86400.0)
    throw ConfigError("parameter 'master_timeout_s' = " + std::to_string(timeout_s) +
                      " s must be in (0, 86400] s (how long the ROS master may be unreachable)");
}

double MasterWatchdog::lostFor(double now_s) const {
  return state_ == State::Ok || !seen_ ? 0.0 : std::max(0.0, now_s - lost_since_s_);
}

MasterWatchdog::Event MasterWatchdog::update(double now_s, bool reachable, long master_pid) {
  if (!seen_) {
    seen_ = true;
    last_ok_s_ = now_s;
  }
  if (state_ == State::TimedOut || state_ == State::Restarted) return Event::None;
  const std::string master = "the ROS master at " + uri_;
  if (reachable) {
    const bool other = master_pid >= 0 && pid_ >= 0 && master_pid != pid_;
    if (master_pid >= 0 && pid_ < 0) pid_ = master_pid;
    const double gone = state_ == State::Lost ? now_s - lost_since_s_ : 0.0;
    const State before = state_;
    last_ok_s_ = now_s;
    if (other) {
      state_ = State::Restarted;
      message_ = master + " answers again" + (before == State::Lost ? " after " + seconds(gone) : std::string()) +
                 ", but it is a new master (pid " + std::to_string(master_pid) + ", was " + std::to_string(pid_) +
                 "): this node's topics and services are not registered with it";
      return Event::Restarted;
    }
    if (before != State::Lost) return Event::None;
    state_ = State::Ok;
    message_ = master + " is back after " + seconds(gone);
    return Event::Back;
  }
  if (state_ == State::Ok) {
    state_ = State::Lost;
    lost_since_s_ = last_ok_s_;
    message_ = master + " is unreachable (gone for " + seconds(now_s - lost_since_s_) +
               "); waiting up to master_timeout_s = " + seconds(timeout_s_) + " for it to come back";
    return Event::Lost;
  }
  if (now_s - lost_since_s_ >= timeout_s_) {
    state_ = State::TimedOut;
    message_ = master + " has been unreachable for " + seconds(now_s - lost_since_s_) +
               " (master_timeout_s = " + seconds(timeout_s_) + ")";
    return Event::TimedOut;
  }
  return Event::None;
}

const char* toString(MasterWatchdog::Event e) {
  switch (e) {
    case MasterWatchdog::Event::None:
      return "none";
    case MasterWatchdog::Event::Lost:
      return "lost";
    case MasterWatchdog::Event::Back:
      return "back";
    case MasterWatchdog::Event::TimedOut:
      return "timed out";
    case MasterWatchdog::Event::Restarted:
      return "restarted";
  }
  return "?";
}

}  // namespace scanstop
