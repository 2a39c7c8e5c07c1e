#pragma once
/// The explorer's parameters by name: the one list that explorer_node (ROS parameters) and the
/// offline tools (plan_step, floor_coverage: `--config config/explorer.yaml`) read, so that a tool
/// plans with the same configuration as a mission.

#include <string>

#include "scanstop_common/robot_body.h"
#include "scanstop_explorer/explorer.h"

namespace scanstop {
namespace explorer {

/// Calls visit(name, field) for every parameter of ExplorerConfig that is read by its own name (the
/// field's name, with its unit). The body-derived robot_radius_m and robot_height_m are not in it:
/// see applyBody().
template <class Visit>
void forEachParameter(ExplorerConfig& c, Visit&& visit) {
  visit("resolution_m", c.floor.resolution_m);
  visit("floor_layer_m", c.floor.floor_layer_m);
  visit("grid_margin_m", c.floor.grid_margin_m);
  visit("min_floor_points", c.floor.min_floor_points);
  visit("min_obstacle_points", c.floor.min_obstacle_points);
  visit("floor_fill_radius_m", c.floor.floor_fill_radius_m);
  visit("speckle_min_points", c.floor.speckle_min_points);
  visit("speckle_max_cells", c.floor.speckle_max_cells);
  visit("min_obstacle_scans", c.floor.min_obstacle_scans);
  visit("d_max_m", c.planner.d_max_m);
  visit("k_r_m", c.planner.k_r_m);
  visit("k0", c.planner.k0);
  visit("c0", c.planner.c0);
  visit("knowledge_threshold", c.planner.knowledge_threshold);
  visit("frontier_distance_m", c.planner.frontier_distance_m);
  visit("occluded_frontier_knowledge", c.planner.occluded_frontier_knowledge);
  visit("occluded_frontier_min_m", c.planner.occluded_frontier_min_m);
  visit("frontier_min_unknown_m", c.planner.frontier_min_unknown_m);
  visit("ignore_wall_base_frontier", c.planner.ignore_wall_base_frontier);
  visit("start_snap_m", c.planner.start_snap_m);
  visit("target_clearance_m", c.planner.target_clearance_m);
  visit("max_coverage_landmarks", c.planner.max_coverage_landmarks);
  visit("knowledge_model", c.planner.knowledge_model);
  visit("target_score", c.planner.target_score);
  visit("gain_sample_m", c.planner.gain_sample_m);
  visit("max_gain_samples", c.planner.max_gain_samples);
  visit("min_gain_m2", c.planner.min_gain_m2);
  visit("gain_cells", c.planner.gain_cells);
  visit("min_open_area_m2", c.planner.min_open_area_m2);
  visit("beyond_reach_min_m2", c.planner.beyond_reach_min_m2);
  visit("view_beyond_reach_m", c.planner.view_beyond_reach_m);
  visit("rescan_distance_m", c.planner.rescan_distance_m);
  visit("known_free_radius_m", c.known_free_radius_m);
  visit("self_filter_radius_m", c.self_filter_radius_m);
  visit("target_tolerance_m", c.target_tolerance_m);
  visit("progress_m", c.progress_m);
  visit("max_failed_attempts", c.max_failed_attempts);
  visit("blacklist_radius_m", c.blacklist_radius_m);
  visit("contact_radius_m", c.contact_radius_m);
}

/// The margins the explorer adds to the robot's body (config/robot_body.yaml).
struct BodyMargins {
  double inflation_margin_m = 0.04;        ///< robot_radius_m = body radius + this [m], [0, 1]
  double obstacle_height_margin_m = 0.03;  ///< the obstacle layer's top = body height + this [m], [0, 1]
  /// Throws ConfigError naming the margin.
  void validate() const;
};

/// Sets c.planner.robot_radius_m and c.floor.robot_height_m from the body and the margins (the
/// obstacle layer starts above the floor layer, so its thickness is the top minus half of it).
void applyBody(const RobotBody& body, const BodyMargins& margins, ExplorerConfig& c);

/// Reads an explorer parameter file (a YAML map of name: value, e.g. config/explorer.yaml) over c:
/// the names of forEachParameter, inflation_margin_m and obstacle_height_margin_m (applied to the
/// default RobotBody, which equals config/robot_body.yaml), robot_radius_m and robot_height_m (set
/// explicitly, they override the body). Throws IoError for an unreadable file and ConfigError for an
/// unknown name, a value of the wrong type or out of range, each naming the file and the parameter.
void readParameterFile(const std::string& path, ExplorerConfig& c);

/// The configuration as a parameter file that readParameterFile() reads back to the same c: every
/// name of forEachParameter, and robot_radius_m and robot_height_m as they are (from the body or set).
/// `comment` goes first, as '#' lines.
std::string parameterFileText(const ExplorerConfig& c, const std::string& comment = "");

}  // namespace explorer
}  // namespace scanstop
