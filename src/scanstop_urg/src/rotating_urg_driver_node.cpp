#include <ros/ros.h>

#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_urg/urg_driver_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "rotating_urg_driver");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::urg::UrgDriverNode node(nh, pnh);
    // The ROS master gone: ERROR once (the scanner does not move the robot; a running scan ends as
    // usual); gone longer than master_timeout_s (or a new master): end.
    scanstop::RosMasterWatchdog watchdog("rotating_urg_driver", master_timeout_s);
    ros::AsyncSpinner spinner(3);  // a 40 s scan must not stop diagnostics and reconnects
    spinner.start();
    ros::waitForShutdown();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("rotating_urg_driver: %s", e.what());
    return 1;
  }
  return 0;
}
