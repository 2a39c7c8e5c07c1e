#include <ros/ros.h>

#include "scanstop_mesher/bpa_mesher_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "bpa_mesher_node");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::mesher::BpaMesherNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("bpa_mesher_node: %s", e.what());
    return 1;
  }
  return 0;
}
