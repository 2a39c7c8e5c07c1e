// explorer_node: see scanstop_explorer/explorer_ros.h.
#include "scanstop_common/error.h"
#include "scanstop_explorer/explorer_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "explorer_node");
  // The handles outlive the try: when the last one goes, ros::shutdown() runs and a ROS_FATAL
  // naming a bad parameter would no longer be printed.
  ros::NodeHandle nh, pnh("~");
  try {
    scanstop::explorer::ExplorerNode node(nh, pnh);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("explorer_node: %s", e.what());
    return 1;
  }
  return 0;
}
