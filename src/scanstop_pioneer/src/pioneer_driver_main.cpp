#include <ros/ros.h>

#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_pioneer/pioneer_driver_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "pioneer_driver");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::pioneer::PioneerDriverNode node(nh, pnh);
    // The ROS master gone: stop the robot (safety); gone longer than master_timeout_s: end.
    scanstop::RosMasterWatchdog::Handlers handlers;
    handlers.on_lost = [&node](const std::string& why) { node.onMasterLost(why); };
    handlers.on_back = [&node](const std::string&) { node.onMasterBack(); };
    handlers.on_end = [&node](const std::string& why) {
      node.onMasterLost(why);
      ros::requestShutdown();
    };
    scanstop::RosMasterWatchdog watchdog("pioneer_driver", master_timeout_s, handlers);
    // Motions block their service call; the other threads keep cmd_vel and diagnostics going.
    ros::AsyncSpinner spinner(3);
    spinner.start();
    ros::waitForShutdown();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("pioneer_driver: %s", e.what());
    return 1;
  }
  return 0;
}
