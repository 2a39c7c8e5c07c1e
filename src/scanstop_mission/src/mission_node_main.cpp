#include <ros/ros.h>

#include "scanstop_common/error.h"
#include "scanstop_mission/mission_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "mission_node");
  ros::NodeHandle nh, pnh("~");
  // Spin before the node is built: resuming a saved mission (in the constructor) waits for the
  // latched odom and slam/path messages.
  ros::AsyncSpinner spinner(2);
  spinner.start();
  try {
    scanstop::mission::MissionNode node(nh, pnh);
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL("mission_node: %s", e.what());
    return 1;
  }
  return 0;
}
