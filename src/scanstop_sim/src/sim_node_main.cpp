#include <ros/ros.h>

#include <string>

#include "scanstop_common/ros/launch_control.h"
#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_sim/sim_node.h"

int main(int argc, char** argv) {
  scanstop::sim::keepLargeBuffersMapped();
  ros::init(argc, argv, "sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::sim::SimNode node(nh, pnh);
    // The ROS master gone: refuse motions (the robot stands); gone longer than master_timeout_s: end.
    scanstop::RosMasterWatchdog::Handlers handlers;
    handlers.on_lost = [&node](const std::string& why) { node.onMasterLost(why); };
    handlers.on_back = [&node](const std::string&) { node.onMasterBack(); };
    handlers.on_end = [&node](const std::string& why) {
      node.onMasterLost(why);
      ros::requestShutdown();
    };
    scanstop::RosMasterWatchdog watchdog("sim_node", master_timeout_s, handlers);
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
    scanstop::endLaunchOnSetupError(pnh, "sim_node");
    return 1;
  }
  return 0;
}
