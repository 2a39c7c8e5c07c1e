#pragma once
/// mission_node wires the scan-stop cycle (scanstop_mission core) to ROS: it reads and validates the
/// parameters, calls the scanner, base, SLAM, explorer and mesher services through RosRobotSystem,
/// offers mission/start|pause|resume|abort, publishes mission/status and writes the run report.

#include <ros/ros.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <memory>
#include <thread>

#include "scanstop_mission/mission.h"
#include "scanstop_mission/ros_robot_system.h"

namespace scanstop {
namespace mission {

class MissionNode {
 public:
  /// Reads the parameters from `pnh`; throws ConfigError naming a bad one.
  MissionNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  ~MissionNode();

 private:
  bool onStart(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onAbort(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  void publishStatus(const ros::WallTimerEvent&);
  void runMission();

  ros::NodeHandle nh_;
  MissionConfig config_;
  bool shutdown_when_done_ = false;
  std::unique_ptr<RosRobotSystem> robot_;
  std::unique_ptr<Mission> mission_;
  std::thread runner_;
  std::atomic<bool> running_{false};
  ros::ServiceServer start_srv_, pause_srv_, resume_srv_, abort_srv_;
  ros::Publisher status_pub_;
  ros::WallTimer status_timer_;
};

}  // namespace mission
}  // namespace scanstop
