#include <ros/ros.h>

#include "scanstop_pioneer/pioneer_driver_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "pioneer_driver");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::pioneer::PioneerDriverNode node(nh, pnh);
    // Motions block their service call; the other threads keep cmd_vel and diagnostics going.
    ros::AsyncSpinner spinner(3);
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL("pioneer_driver: %s", e.what());
    return 1;
  }
  return 0;
}
