#pragma once
/// mission_node wires the scan-stop cycle (scanstop_mission core) to ROS: it reads and validates the
/// parameters, calls the scanner, base, SLAM, explorer and mesher services through RosRobotSystem,
/// offers mission/start|pause|resume|abort, publishes mission/status and writes the run report.

#include <ros/ros.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "scanstop_common/cloud.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"
#include "scanstop_mission/mission.h"
#include "scanstop_mission/report.h"
#include "scanstop_mission/ros_robot_system.h"

namespace scanstop {
namespace mission {

class MissionNode {
 public:
  /// Reads the parameters from `pnh`; throws ConfigError naming a bad one.
  MissionNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  ~MissionNode();

  /// ~master_timeout_s [s]: how long the ROS master may be gone before the mission ends.
  double masterTimeout() const { return master_timeout_s_; }
  /// The master watchdog's handlers. Lost: the mission pauses (state kept and saved; the step that
  /// was running ends as its service call does). Back: it resumes, unless the user had paused it.
  /// End (gone longer than master_timeout_s, or a new master): the mission ends FAILED naming the
  /// reason (state, report and summary written; restarting mission_node resumes it), then the node.
  void onMasterLost(const std::string& why);
  void onMasterBack(const std::string& why);
  void onMasterEnd(const std::string& why);

 private:
  bool onStart(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onPause(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onResume(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool onAbort(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  void publishStatus(const ros::WallTimerEvent&);
  void runMission();
  void onStaticTf(const tf2_msgs::TFMessage::ConstPtr& msg);
  /// The ground-truth coverage of the final map when world_file is set (simulation), else none.
  /// mesh_file: the mesh built at the end (empty: none), measured against the world too.
  std::optional<TrueCoverage> trueCoverage(const std::string& mesh_file);
  /// Adds the surface coverage of the map to truth, and the mesh's accuracy when mesh_file is set
  /// (simulation; a failure is a warning).
  void surfaceCoverage(const TriangleMesh& world, const Pose2D& start, const MapDirectory& map, double robot_radius,
                       const std::string& mesh_file, TrueCoverage& truth);

  ros::NodeHandle nh_;
  MissionConfig config_;
  bool shutdown_when_done_ = false;
  bool html_report_ = true;    ///< run make_report.py after report.md
  std::string report_script_;  ///< its path (default: beside this executable)
  double master_timeout_s_ = 30.0;
  std::atomic<bool> paused_for_master_{false};  ///< the watchdog paused the mission (it resumes it)
  std::unique_ptr<RosRobotSystem> robot_;
  std::unique_ptr<Mission> mission_;
  std::thread runner_;
  std::atomic<bool> running_{false};
  ros::ServiceServer start_srv_, pause_srv_, resume_srv_, abort_srv_;
  ros::Publisher status_pub_;
  ros::WallTimer status_timer_;
  std::string map_dir_;
  // Ground-truth coverage in simulation: the world mesh, and sim_node's static world -> map (the start).
  std::string world_file_, world_frame_ = "world", map_frame_ = "map";
  double robot_radius_m_ = 0.3;
  bool robot_radius_given_ = false;  ///< ~robot_radius set; otherwise the explorer's robot_radius_m
  /// The explorer's configuration of this run (explorer_node writes it into its run_dir): the true
  /// coverage rebuilds the floor map with it.
  std::string explorer_config_;
  /// Before the mission's first step, wait up to this long until something subscribes to
  /// mission/status (the launch's rosbag recorder with record:=true), so that the bag holds the first
  /// scan [s]; 0: do not wait.
  double wait_for_recorder_s_ = 0.0;
  int surface_planes_ = 100;  ///< planes of the visible surface's candidate scans; 0: no surface coverage
  ros::Subscriber static_tf_sub_;
  std::mutex start_mutex_;
  std::optional<Pose2D> world_T_map_;
};

}  // namespace mission
}  // namespace scanstop
