#pragma once
/// The ROS master watchdog every node of the workspace runs (issue #22 class 5): checks the master
/// (XML-RPC getPid) every period_s on a thread of its own, feeds scanstop::MasterWatchdog (the state
/// machine, ROS-free) and acts on its events:
///  - lost: ROS_ERROR once "<node>: the ROS master at <uri> is unreachable (gone for 1.0 s); ...",
///    then the node's on_lost (mission: pause; drivers: stop the robot);
///  - back: ROS_WARN "... is back after 4.2 s", then on_back (mission: resume what it paused);
///  - gone longer than master_timeout_s, or a new master on the URI: ROS_ERROR naming it, then on_end
///    (default: ros::requestShutdown(); main() returns 1 when ended()).
/// A check that hangs (a master that accepts but does not answer) counts as unreachable after
/// max(2 s, 4 periods). The clock is the wall clock (steady), never /clock.

#include <functional>
#include <memory>
#include <string>
#include <thread>

namespace scanstop {

class RosMasterWatchdog {
 public:
  using Handler = std::function<void(const std::string& message)>;
  struct Handlers {
    Handler on_lost;
    Handler on_back;
    Handler on_end;  ///< timed out or restarted; unset: ros::requestShutdown()
  };
  /// node: the log prefix; timeout_s: the node's `master_timeout_s` parameter (ConfigError when out of range).
  RosMasterWatchdog(std::string node, double timeout_s, Handlers handlers = Handlers(), double period_s = 0.5);
  ~RosMasterWatchdog();
  RosMasterWatchdog(const RosMasterWatchdog&) = delete;
  RosMasterWatchdog& operator=(const RosMasterWatchdog&) = delete;

  /// The master was gone longer than master_timeout_s, or a new master answered: the node ends.
  bool ended() const;
  /// Why it ended (the logged message), or "".
  std::string endReason() const;

 private:
  struct Shared;
  std::shared_ptr<Shared> shared_;  ///< also held by the (detached) checker thread
  std::thread monitor_;             ///< runs the state machine and the handlers; joined on destruction
};

}  // namespace scanstop
