// explorer_node: see scanstop_explorer/explorer_ros.h.
#include "scanstop_common/error.h"
#include "scanstop_explorer/explorer_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer_node");
  try {
    scanstop::explorer::ExplorerNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("explorer_node: %s", e.what());
    return 1;
  }
  return 0;
}
