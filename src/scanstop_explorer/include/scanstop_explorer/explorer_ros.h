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
};

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
  unsigned step_ = 1;  ///< number of the next plan (image prefix step_NNN_)
  ros::Subscriber scan_sub_;
  ros::ServiceServer plan_srv_;
  ros::Publisher floor_pub_, accessible_pub_, distance_pub_, cost_pub_, knowledge_pub_, evaluation_pub_;
  ros::Publisher skeleton_pub_, landmarks_pub_, path_pub_;
};

}  // namespace explorer
}  // namespace scanstop
