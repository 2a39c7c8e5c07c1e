#include <ros/ros.h>

#include "scanstop_sim/sim_node.h"

int main(int argc, char** argv) {
  scanstop::sim::keepLargeBuffersMapped();
  ros::init(argc, argv, "sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::sim::SimNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("sim_node: %s", e.what());
    return 1;
  }
  return 0;
}
