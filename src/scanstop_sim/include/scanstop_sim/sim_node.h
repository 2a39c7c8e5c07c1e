#pragma once
/// sim_node wires the Simulator to ROS: scanner/take_scan, base/rotate, base/forward and sim/reset
/// services (the same scanner/ and base/ services as the hardware drivers), odometry and tf
/// (odom -> base_link, static world -> map and base_link -> laser), ground truth, the world as a
/// marker and a modelled /clock.

#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <scanstop_msgs/AddHiddenObstacle.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/MotionClearance.h>
#include <scanstop_msgs/ResetSim.h>
#include <scanstop_msgs/Rotate.h>
#include <scanstop_msgs/TakeScan.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "scanstop_sim/simulator.h"

namespace scanstop {
namespace sim {

class SimNode {
 public:
  /// Reads and validates the parameters, loads the world; throws ConfigError / IoError naming the
  /// parameter or file that is wrong.
  SimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  /// The master watchdog's handlers: while the ROS master is gone, rotate/forward are refused with
  /// the reason (a simulated motion is computed in one step; the one running ends as modelled).
  void onMasterLost(const std::string& why);
  void onMasterBack();

 private:
  bool onTakeScan(scanstop_msgs::TakeScan::Request& req, scanstop_msgs::TakeScan::Response& res);
  bool onRotate(scanstop_msgs::Rotate::Request& req, scanstop_msgs::Rotate::Response& res);
  bool onForward(scanstop_msgs::Forward::Request& req, scanstop_msgs::Forward::Response& res);
  bool onReset(scanstop_msgs::ResetSim::Request& req, scanstop_msgs::ResetSim::Response& res);
  bool onAddHiddenObstacle(scanstop_msgs::AddHiddenObstacle::Request& req,
                           scanstop_msgs::AddHiddenObstacle::Response& res);
  /// Runs one motion: refused (`refused` says why) while another one runs; with motion_time_scale
  /// > 0 it takes its modelled duration on the wall clock, during which odom carries its twist and
  /// scanner/take_scan is refused.
  MotionOutput runMotion(const std::function<MotionOutput()>& motion, double distance_m, double angle_rad,
                         std::string* refused);
  void onClockTimer(const ros::WallTimerEvent&);
  /// Writes the simulation state to state_file_ (atomically; errors are logged, not fatal).
  void persistState();
  /// Publishes /clock, odom, tf and ground truth for the current state; with `persist`, saves the
  /// state to state_file first.
  void publishState(bool persist = true);
  void publishStaticTransforms();
  void publishWorldMarker();
  /// A new /tf subscriber (rviz started later, a late node) gets the recent odom -> base_link
  /// transforms (the last kRecentTf steps) once: with the modelled clock they only change at steps,
  /// re-sending them to everybody with the same stamps would make every tf listener warn about
  /// repeated data, and a latched last scan needs the transform at its own stamp.
  void onTfSubscriber(const ros::SingleSubscriberPublisher& pub);
  ros::Time now() const;

  std::unique_ptr<Simulator> sim_;
  std::mutex mutex_;
  std::atomic<bool> moving_{false};     ///< a rotate/forward motion is running
  std::mutex master_mutex_;             ///< guards master_lost_ (mutex_ is held through a scan)
  std::string master_lost_;             ///< non-empty while the ROS master is gone
  double motion_time_scale_ = 0.0;      ///< wall seconds per modelled second of motion (0: at once)
  double scan_time_scale_ = 0.0;        ///< wall seconds per modelled second of a scan (0: at once)
  double world_display_max_z_m_ = 2.0;  ///< sim/world_mesh leaves out triangles wholly above this [m]
  std::string state_file_;              ///< where the simulation state is kept after every step ("" = nowhere)
  bool publish_clock_ = false;
  bool odom_as_map_ = false;  ///< publish map -> odom as identity (no SLAM running)
  double clock_start_s_ = 1.0;
  std::string world_frame_ = "world", map_frame_ = "map", odom_frame_ = "odom", base_frame_ = "base_link",
              laser_frame_ = "laser";
  ros::ServiceServer take_scan_srv_, rotate_srv_, forward_srv_, reset_srv_, hidden_obstacle_srv_;
  /// A hidden obstacle waiting for the next forward motion that reaches it (base_link x, y, radius).
  std::optional<Simulator::HiddenObstacle> armed_obstacle_;
  /// Places armed_obstacle_ when a forward motion of distance_m reaches it (under mutex_).
  void placeArmedObstacle(double distance_m);
  ros::Publisher clock_pub_, odom_pub_, truth_pub_, scan_pub_, progress_pub_, marker_pub_;
  ros::Publisher clearance_pub_;  ///< ground_truth/clearance: one MotionClearance per motion
  uint32_t motion_index_ = 0;
  /// Publishes the motion's true clearance (before the call is answered).
  void publishClearance(const char* motion, double command, const MotionOutput& out);
  tf2_ros::TransformBroadcaster tf_;
  ros::Publisher tf_connect_pub_;  ///< the same /tf publication, for onTfSubscriber
  std::mutex tf_mutex_;
  static constexpr size_t kRecentTf = 32;
  std::deque<geometry_msgs::TransformStamped> recent_odom_tf_;  ///< oldest first, distinct stamps
  tf2_ros::StaticTransformBroadcaster static_tf_;
  ros::WallTimer clock_timer_;
};

}  // namespace sim
}  // namespace scanstop
