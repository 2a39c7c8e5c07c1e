#include <ros/ros.h>

#include "scanstop_common/error.h"
#include "scanstop_common/ros/master_watchdog.h"
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
    // The ROS master gone: the mission pauses, keeping its state; back: it resumes; gone longer than
    // master_timeout_s (or a new master): the mission ends FAILED naming why, then the node (exit 1).
    scanstop::RosMasterWatchdog::Handlers handlers;
    handlers.on_lost = [&node](const std::string& why) { node.onMasterLost(why); };
    handlers.on_back = [&node](const std::string& why) { node.onMasterBack(why); };
    handlers.on_end = [&node](const std::string& why) { node.onMasterEnd(why); };
    scanstop::RosMasterWatchdog watchdog("mission_node", node.masterTimeout(), handlers);
    ros::waitForShutdown();
    if (watchdog.ended()) return 1;
  } catch (const std::exception& e) {
    ROS_FATAL("mission_node: %s", e.what());
    return 1;
  }
  return 0;
}
