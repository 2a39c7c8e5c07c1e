#include <ros/ros.h>
#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>

#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_sim/sim_node.h"

namespace {
/// Whether this process was started by roslaunch (its parent's command line names it).
bool parentIsRoslaunch() {
  std::ifstream in("/proc/" + std::to_string(::getppid()) + "/cmdline", std::ios::binary);
  const std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return cmdline.find("roslaunch") != std::string::npos;
}
}  // namespace

int main(int argc, char** argv) {
  scanstop::sim::keepLargeBuffersMapped();
  ros::init(argc, argv, "sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout", master_timeout);
    scanstop::sim::SimNode node(nh, pnh);
    // The ROS master gone: refuse motions (the robot stands); gone longer than master_timeout: end.
    scanstop::RosMasterWatchdog::Handlers handlers;
    handlers.on_lost = [&node](const std::string& why) { node.onMasterLost(why); };
    handlers.on_back = [&node](const std::string&) { node.onMasterBack(); };
    handlers.on_end = [&node](const std::string& why) {
      node.onMasterLost(why);
      ros::requestShutdown();
    };
    scanstop::RosMasterWatchdog watchdog("sim_node", master_timeout, handlers);
    // Several threads: a scan request during a (wall-clock timed) motion is answered at once.
    ros::AsyncSpinner spinner(3);
    spinner.start();
    ros::waitForShutdown();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("sim_node: %s", e.what());
    // A start-up error (world file, start pose, parameters) repeats on every respawn: with
    // ~end_launch_on_setup_error (sim_explore.launch sets it) the launch ends here, at once, instead
    // of respawning sim_node while the mission waits for its services (issue 22).
    bool end_launch = false;
    pnh.param("end_launch_on_setup_error", end_launch, false);
    if (end_launch && parentIsRoslaunch()) {
      ROS_FATAL("sim_node: ending the launch: every restart would fail the same way");
      // roslaunch interrupted while it still starts the other nodes hangs ~20 s in its shutdown
      // (measured): give it time to finish starting them (this process being alive, no respawn).
      ::sleep(3);
      ::kill(::getppid(), SIGINT);
    }
    return 1;
  }
  return 0;
}
