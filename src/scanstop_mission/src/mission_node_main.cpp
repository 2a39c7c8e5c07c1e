#include <ros/ros.h>

#include "scanstop_common/error.h"
#include "scanstop_mission/mission_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "mission_node");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::mission::MissionNode node(nh, pnh);
    ros::AsyncSpinner spinner(2);
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL("mission_node: %s", e.what());
    return 1;
  }
  return 0;
}
