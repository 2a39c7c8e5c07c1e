#include "scanstop_common/ros/launch_control.h"

#include <ros/console.h>
#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <iterator>

namespace scanstop {

bool parentIsRoslaunch() {
  std::ifstream in("/proc/" + std::to_string(::getppid()) + "/cmdline", std::ios::binary);
  const std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return cmdline.find("roslaunch") != std::string::npos;
}

bool interruptParentLaunch() { return parentIsRoslaunch() && ::kill(::getppid(), SIGINT) == 0; }

bool endLaunchOnSetupError(const ros::NodeHandle& pnh, const std::string& node) {
  bool end_launch = false;
  pnh.param("end_launch_on_setup_error", end_launch, false);
  if (!end_launch || !parentIsRoslaunch()) return false;
  ROS_FATAL("%s: ending the launch: every restart would fail the same way", node.c_str());
  ::sleep(3);
  return interruptParentLaunch();
}

}  // namespace scanstop
