#include <ros/ros.h>

#include "scanstop_common/ros/launch_control.h"
#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_mesher/bpa_mesher_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "bpa_mesher_node");
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::mesher::BpaMesherNode node(nh, pnh);
    // The ROS master gone: ERROR once; gone longer than master_timeout_s (or a new master): end.
    scanstop::RosMasterWatchdog watchdog("bpa_mesher_node", master_timeout_s);
    ros::spin();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("bpa_mesher_node: %s", e.what());
    // A start-up error (a map_dir that is a file, a bad parameter) repeats on every respawn: with
    // ~end_launch_on_setup_error the launch ends instead (issue 22).
    scanstop::endLaunchOnSetupError(pnh, "bpa_mesher_node");
    return 1;
  }
  return 0;
}
