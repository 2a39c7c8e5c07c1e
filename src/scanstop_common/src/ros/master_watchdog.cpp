#include "scanstop_common/ros/master_watchdog.h"

#include <ros/master.h>
#include <ros/ros.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <utility>

#include "scanstop_common/master_watchdog.h"

namespace scanstop {

namespace {

double steadyNow() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

struct RosMasterWatchdog::Shared {
  Shared(std::string n, double timeout_s, Handlers h, double p)
      : node(std::move(n)), core(ros::master::getURI(), timeout_s), handlers(std::move(h)), period_s(p) {}
  const std::string node;
  MasterWatchdog core;
  const Handlers handlers;
  const double period_s;
  std::mutex mutex;
  std::condition_variable cv;
  bool stop = false;
  // The checker thread's results.
  bool last_ok = true;
  long last_pid = -1;
  double check_started_s = -1.0;  ///< >= 0 while a check runs
  bool have_result = false;
  bool ended = false;
  std::string end_reason;
  bool checker_exited = false;
};

RosMasterWatchdog::RosMasterWatchdog(std::string node, double timeout_s, Handlers handlers, double period_s)
    : shared_(std::make_shared<Shared>(std::move(node), timeout_s, std::move(handlers), std::max(0.05, period_s))) {
  // The checker: may hang inside an XML-RPC call to a master that does not answer, so it is
  // detached and owns a reference to the shared state; the monitor decides from its results.
  std::shared_ptr<Shared> s = shared_;
  std::thread([s] {
    std::unique_lock<std::mutex> lock(s->mutex);
    while (!s->stop) {
      s->check_started_s = steadyNow();
      lock.unlock();
      XmlRpc::XmlRpcValue args, result, payload;
      args[0] = ros::this_node::getName();
      const bool ok = ros::master::execute("getPid", args, result, payload, false);
      long pid = -1;
      if (ok && payload.getType() == XmlRpc::XmlRpcValue::TypeInt) pid = static_cast<int>(payload);
      lock.lock();
      s->check_started_s = -1.0;
      s->last_ok = ok;
      s->last_pid = pid;
      s->have_result = true;
      s->cv.notify_all();
      s->cv.wait_for(lock, std::chrono::duration<double>(s->period_s), [&] { return s->stop; });
    }
    s->checker_exited = true;
    s->cv.notify_all();
  }).detach();
  monitor_ = std::thread([s] {
    const double hung_after_s = std::max(2.0, 4.0 * s->period_s);
    std::unique_lock<std::mutex> lock(s->mutex);
    while (!s->stop) {
      s->cv.wait_for(lock, std::chrono::duration<double>(s->period_s), [&] { return s->stop; });
      if (s->stop || !s->have_result) continue;
      const double now = steadyNow();
      const bool hung = s->check_started_s >= 0.0 && now - s->check_started_s > hung_after_s;
      const bool reachable = s->last_ok && !hung;
      const MasterWatchdog::Event e = s->core.update(now, reachable, reachable ? s->last_pid : -1);
      if (e == MasterWatchdog::Event::None) continue;
      const std::string message = s->core.message();
      if (e == MasterWatchdog::Event::TimedOut || e == MasterWatchdog::Event::Restarted) {
        s->ended = true;
        s->end_reason = message;
      }
      lock.unlock();
      switch (e) {
        case MasterWatchdog::Event::Lost:
          ROS_ERROR("%s: %s", s->node.c_str(), message.c_str());
          if (s->handlers.on_lost) s->handlers.on_lost(message);
          break;
        case MasterWatchdog::Event::Back:
          ROS_WARN("%s: %s", s->node.c_str(), message.c_str());
          if (s->handlers.on_back) s->handlers.on_back(message);
          break;
        default:
          ROS_ERROR("%s: %s; the node ends", s->node.c_str(), message.c_str());
          if (s->handlers.on_end)
            s->handlers.on_end(message);
          else
            ros::requestShutdown();
          break;
      }
      lock.lock();
    }
  });
}

RosMasterWatchdog::~RosMasterWatchdog() {
  {
    std::unique_lock<std::mutex> lock(shared_->mutex);
    shared_->stop = true;
    shared_->cv.notify_all();
    // Let a check in progress finish (it is quick unless the master hangs), so that the checker is
    // not inside roscpp's XML-RPC client while the process exits.
    shared_->cv.wait_for(lock, std::chrono::seconds(1), [this] { return shared_->checker_exited; });
  }
  if (monitor_.joinable()) monitor_.join();
}

bool RosMasterWatchdog::ended() const {
  std::lock_guard<std::mutex> lock(shared_->mutex);
  return shared_->ended;
}

std::string RosMasterWatchdog::endReason() const {
  std::lock_guard<std::mutex> lock(shared_->mutex);
  return shared_->end_reason;
}

}  // namespace scanstop
