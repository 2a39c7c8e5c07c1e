#include <ros/ros.h>

#include "scanstop_urg/urg_driver_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "rotating_urg_driver");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::urg::UrgDriverNode node(nh, pnh);
    ros::AsyncSpinner spinner(3);  // a 40 s scan must not stop diagnostics and reconnects
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL("rotating_urg_driver: %s", e.what());
    return 1;
  }
  return 0;
}
