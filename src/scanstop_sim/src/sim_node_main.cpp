#include <ros/ros.h>

#include "scanstop_sim/sim_node.h"

int main(int argc, char** argv) {
  scanstop::sim::keepLargeBuffersMapped();
  ros::init(argc, argv, "sim_node");
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::sim::SimNode node(nh, pnh);
    // Several threads: a scan request during a (wall-clock timed) motion is answered at once.
    ros::AsyncSpinner spinner(3);
    spinner.start();
    ros::waitForShutdown();
  } catch (const std::exception& e) {
    ROS_FATAL("sim_node: %s", e.what());
    return 1;
  }
  return 0;
}
