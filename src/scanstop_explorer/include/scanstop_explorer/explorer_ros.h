#pragma once
/// explorer_node: wires the exploration core to ROS. Subscribes the registered scans (each once,
/// plus the map directory at start), serves explorer/plan_next and publishes the step's grids,
/// skeleton, landmarks and path; writes per-step PNG images into the run directory.

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <scanstop_msgs/PlanNext.h>
#include <scanstop_msgs/RegisteredScan.h>

#include <memory>
#include <string>

#include "scanstop_explorer/explorer.h"

namespace scanstop {
namespace explorer {

/// Node parameters besides the algorithm's (all read and validated in readParameters()).
struct NodeConfig {
  std::string frame_id = "map";  ///< frame of the grids, markers and path
  std::string map_dir;           ///< map directory to load at start and before each plan ("" = none)
  std::string run_dir;           ///< where per-step images go ("" = none)
  int image_scale = 2;           ///< image pixels per cell, [1, 16]
  /// Request checks: a map_pose or unreachable point farther than this from the map origin is
  /// refused as absurd [m], [1, 1e6]
  double max_coordinate_m = 1000.0;
  /// a registered scan with a point farther than this from its pose is dropped (it would blow up
  /// the floor grid) [m], [0.1, 1000]
  double max_point_distance_m = 100.0;
  int max_unreachable = 10000;  ///< most unreachable points one request may carry, [0, 1e6]
};

/// Why a plan_next request cannot be served, or "" when it can: map_pose in another frame than
/// frame_id (empty = frame_id), a non-finite position or orientation, a non-unit quaternion, a
/// coordinate beyond max_coordinate_m, too many or non-finite or absurd unreachable points.
/// Checked before anything is applied (the blacklist, the map directory, the step counter).
std::string planRequestProblem(const scanstop_msgs::PlanNext::Request& req, const NodeConfig& node_config);

/// Reads ~parameters into the configs; throws ConfigError naming the bad parameter.
void readParameters(const ros::NodeHandle& pnh, ExplorerConfig& config, NodeConfig& node_config);

class ExplorerNode {
 public:
  /// nh: topic namespace (relative names, meant to be remapped); pnh: private parameters.
  ExplorerNode(ros::NodeHandle nh, ros::NodeHandle pnh);

 private:
  void onScan(const scanstop_msgs::RegisteredScan& msg);
  bool onPlanNext(scanstop_msgs::PlanNext::Request& req, scanstop_msgs::PlanNext::Response& res);
  void loadMapDir();
  void publish(const PlanResult& r);
  void writeImages(const PlanResult& r);
  nav_msgs::OccupancyGrid gridMsg(const PlanResult& r) const;

  ros::NodeHandle nh_;
  NodeConfig node_config_;
  std::unique_ptr<Explorer> explorer_;
  unsigned step_ = 1;            ///< number of the next plan (image prefix step_NNN_)
  std::string config_text_;      ///< the configuration as a parameter file (run_dir/config.yaml)
  bool config_written_ = false;  ///< written with the first plan's files
  ros::Subscriber scan_sub_;
  ros::ServiceServer plan_srv_;
  ros::Publisher floor_pub_, accessible_pub_, distance_pub_, cost_pub_, knowledge_pub_, evaluation_pub_;
  ros::Publisher skeleton_pub_, landmarks_pub_, path_pub_;
};

}  // namespace explorer
}  // namespace scanstop
