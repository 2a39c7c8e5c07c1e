// explorer_node: see scanstop_explorer/explorer_ros.h.
#include "scanstop_common/error.h"
#include "scanstop_common/ros/launch_control.h"
#include "scanstop_common/ros/master_watchdog.h"
#include "scanstop_common/ros/params.h"
#include "scanstop_explorer/explorer_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer_node");
  // The handles outlive the try: when the last one goes, ros::shutdown() runs and a ROS_FATAL
  // naming a bad parameter would no longer be printed.
  ros::NodeHandle nh, pnh("~");
  try {
    double master_timeout_s = 30.0;
    scanstop::ros_params::optional(pnh, "master_timeout_s", master_timeout_s);
    scanstop::explorer::ExplorerNode node(nh, pnh);
    // The ROS master gone: ERROR once; gone longer than master_timeout_s (or a new master): end.
    scanstop::RosMasterWatchdog watchdog("explorer_node", master_timeout_s);
    ros::spin();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("explorer_node: %s", e.what());
    // A start-up error (a map_dir that is a file, a bad parameter) repeats on every respawn: with
    // ~end_launch_on_setup_error the launch ends instead (issue 22).
    scanstop::endLaunchOnSetupError(pnh, "explorer_node");
    return 1;
  }
  return 0;
}
