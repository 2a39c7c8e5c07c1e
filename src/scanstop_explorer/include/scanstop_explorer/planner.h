#pragma once
/// One exploration step (thesis Algorithm 5): floor grid -> distance transform -> accessible floor
/// -> skeleton and landmarks -> direct-reachability graph -> cost, knowledge and evaluation maps ->
/// next scan point and path -> termination test. Every stage is its own function.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/pose.h"
#include "scanstop_explorer/grid.h"

namespace scanstop {
namespace explorer {

/// Parameters of a planning step. Defaults are the thesis' (5.4) where it gives them.
struct PlannerConfig {
  double robot_radius_m = 0.3;       ///< floor closer than this to a non-floor cell is not accessible [m], (0, 5]
  double d_max_m = 2.0;              ///< longest straight movement [m], (0, 50]
  double k_r_m = 1.0;                ///< knowledge enhancement radius of a scan [m], (0, 50]
  double k0 = 1.0;                   ///< knowledge offset in b, (0, 1e6]
  double c0 = 3.0;                   ///< cost offset in b [m], (0, 1e6]
  double knowledge_threshold = 1.0;  ///< a cell lacks knowledge when k < this, (0, 1e6]
  double frontier_distance_m = 0.5;  ///< a cell borders unknown space when a frontier cell is this close [m], (0, 50]
  /// Occluded frontiers (termination and targets): a reached cell near a frontier cell that no scan
  /// within k_r_m has in plain sight (straight line over floor cells only; e.g. the part of a
  /// corridor hidden behind the door jambs) stays open until its knowledge reaches this value,
  /// even if the knowledge disc of a nearby scan covers it. <= knowledge_threshold: off (the
  /// knowledge rule alone), [0, 1e6]
  double occluded_frontier_knowledge = 3.0;
  /// Occluded cells of frontier pieces (8-connected) shorter than this (bounding box extent) are
  /// ignored: shadows of chair legs and wall corners, not openings the robot could pass [m], [0, 50]
  double occluded_frontier_min_m = 0.6;
  /// Unknown regions (8-connected) whose bounding box is smaller than this in both directions are
  /// no frontier: pockets enclosed by known cells, such as a wall cell no point fell into, hide no
  /// floor the robot could use (0: every unknown cell next to floor is frontier) [m], [0, 50]
  double frontier_min_unknown_m = 0.6;
  /// Open cells (termination and targets) in 8-connected pieces of less than this area are not
  /// open: a piece of a few cells (one cell next to a small gap in a wall's floor band, a shadow's
  /// tip) sent the robot back across room_10x8 for 6 scans that saw nothing new; the narrowest door
  /// the robot passes (0.8 m: 0.2 m of accessible floor, 0.5 m deep) is 0.1 m^2. 0: every open
  /// cell counts [m^2], [0, 100]
  double min_open_area_m2 = 0.0;
  /// Views beyond reach (termination and targets): floor next to a frontier that the robot cannot
  /// reach yet (seen through a door whose sight cone is narrower than the robot where it starts:
  /// the turtlebot3_house's south hall seen as two wedges from the corridor ended a mission at 67 %
  /// of the floor), in 8-connected pieces of at least this area, makes the reached cells within
  /// view_beyond_reach_m of it open while their knowledge is below occluded_frontier_knowledge: the
  /// robot scans at the door until the floor beyond joins the reachable floor or that many scans
  /// saw it. 0: off [m^2], [0, 1e4]
  double beyond_reach_min_m2 = 0.0;
  /// A new scan location closer than this to a past scan position is not chosen: a scan there sees
  /// what that one saw (turtlebot3_house: the cells near a door counted open until 3 scans had them
  /// in sight, and the explorer chose the robot's own cell, 2 cm away, for a second scan). Not for
  /// goals. 0: off [m], [0, 5]
  double rescan_distance_m = 0.0;
  double view_beyond_reach_m = 1.0;  ///< see beyond_reach_min_m2 [m], (0, 10]
  /// An unknown cell whose only floor neighbours lie beside an obstacle cell (8-neighbours) is no
  /// frontier: it sits in or behind a wall (a wall base's floor cell, a noisy wall's outer face),
  /// not at the edge of a view into unknown space. false: the plain definition.
  bool ignore_wall_base_frontier = true;
  double start_snap_m = 0.5;  ///< robot off the accessible floor: join it within this distance [m], [0, 5]
  /// A chosen target (new scan location or goal) closer than this to a non-floor cell moves to the
  /// nearest reached, not blacklisted cell at least this far from one, if there is one within this
  /// distance of it; otherwise it stays (a door or narrow passage keeps its target). The path's
  /// landmarks lie on the skeleton, far from walls; the last leg ends at the target, and a target
  /// right at the accessible border leaves the robot robot_radius_m minus its own radius against
  /// the drift of that leg. 0: off (the thesis' argmax as it is) [m], [0, 5]
  double target_clearance_m = 0.0;
  int max_coverage_landmarks = 2000;  ///< bound on the landmarks added for cells no landmark sees, [0, 1e6]
  /// What a scan adds to the knowledge map: "disc" (thesis 5.4: 1 to every cell within k_r_m) or
  /// "visibility" (1 to every cell in its plain sight within k_r_m: rays over the floor grid, stopped
  /// by obstacle cells; a cell behind a cabinet gets nothing).
  std::string knowledge_model = "disc";
  /// How the next scan location is chosen among the reached cells that lack knowledge or are open:
  /// "knowledge" (thesis: the argmax of b = 1/(k + k0) * 1/(c + c0)) or "gain" (the argmax of
  /// g / (c + c0), g the expected gain [m^2]: the cells in plain sight within k_r_m that are unknown
  /// or lack knowledge; on a lattice of gain_sample_m; when no candidate's gain reaches min_gain_m2,
  /// the thesis' b).
  std::string target_score = "knowledge";
  double gain_sample_m = 0.25;  ///< lattice of the candidates whose gain is computed [m], (0, 5]
  int max_gain_samples = 3000;  ///< the lattice grows coarser until at most this many candidates remain, [1, 1e6]
  double min_gain_m2 = 0.5;     ///< a candidate that would add less is not chosen by gain [m^2], [0, 1e6]
  /// target_score "gain": what a candidate's gain counts in its plain sight within k_r_m. "lacking":
  /// unknown cells and floor cells that lack knowledge (every cell must be seen from within k_r_m).
  /// "open": unknown cells and open cells (what keeps exploration from completing), every reached
  /// cell a candidate, one that sees no open cell gains nothing (floor already seen from farther
  /// than k_r_m draws no scan).
  std::string gain_cells = "lacking";

  /// Throws ConfigError naming the parameter, its value and the allowed range.
  void validate() const;
};

/// A node of the reachability graph (node 0 of a plan is the robot).
struct Landmark {
  enum Kind { kRobot, kAnchor, kSpecial, kExtra, kCoverage };
  cv::Point cell;
  Kind kind = kAnchor;
  Eigen::Vector2d pos = Eigen::Vector2d::Zero();  ///< continuous cell coordinates (cell centre = cell + 0.5)

  Landmark() = default;
  Landmark(const cv::Point& c, Kind k) : cell(c), kind(k), pos(c.x + 0.5, c.y + 0.5) {}
};
const char* landmarkKindName(Landmark::Kind kind);

// ---- stages ---------------------------------------------------------------------------------

/// Floor-only cells (state == kFloor) as a CV_8U 0/1 mask.
cv::Mat floorMask(const cv::Mat& states);
/// Accessible floor: floor cells whose distance to the nearest non-floor cell is at least the
/// robot radius (sq_dt >= radius_cells^2). CV_8U 0/1.
cv::Mat accessibleFloor(const cv::Mat& sq_dt, double radius_cells);

/// True when the straight segment between two points in continuous cell coordinates (cell (c, r)
/// spans [c, c+1) x [r, r+1)) crosses only accessible cells (exact grid traversal; a segment
/// through a cell corner needs both cells beside the corner).
bool segmentClear(const cv::Mat& accessible, const Eigen::Vector2d& a, const Eigen::Vector2d& b);
/// Segment between two cell centres.
bool segmentClear(const cv::Mat& accessible, const cv::Point& a, const cv::Point& b);

/// Landmarks (thesis 5.3): one anchor per 8-connected anchor component (its pixel with the
/// largest distance), the special points of the skeleton, and extra skeleton points between two
/// landmarks that the skeleton joins but that cannot see each other or are farther apart than
/// d_max_cells (inserted recursively at the middle of the skeleton path).
std::vector<Landmark> selectLandmarks(const cv::Mat& accessible, const cv::Mat& sq_dt, const cv::Mat& anchors,
                                      const cv::Mat& skeleton, double d_max_cells);

/// Direct-reachability graph: an edge joins two nodes whose segment is clear and at most d_max.
struct Graph {
  std::vector<std::vector<std::pair<int, double>>> adjacency;  ///< (node, length [cells])
  size_t edgeCount() const;
};
Graph reachabilityGraph(const std::vector<Landmark>& nodes, const cv::Mat& accessible, double d_max_cells);
/// Adds node `index` (already in `nodes`) to the graph.
void addGraphNode(Graph& graph, const std::vector<Landmark>& nodes, int index, const cv::Mat& accessible,
                  double d_max_cells);

/// Dijkstra over the graph from the seeds (node, distance); dist/pred are updated in place (only
/// improved). Returns the nodes whose distance improved.
std::vector<int> dijkstra(const Graph& graph, const std::vector<std::pair<int, double>>& seeds,
                          std::vector<double>& dist, std::vector<int>& pred);

/// Cost map: travel distance [cells] of every accessible cell reachable by a path robot ->
/// landmarks -> cell (each leg clear and <= d_max), and the node the last leg starts from.
struct CostMap {
  cv::Mat cost;         ///< CV_32F [cells], +inf where unreached
  cv::Mat predecessor;  ///< CV_32S node index, -1 where unreached
  std::vector<Landmark> nodes;
  Graph graph;
  std::vector<double> node_dist;  ///< [cells], +inf unreached
  std::vector<int> node_pred;     ///< -1 for the robot / unreached
  int coverage_landmarks = 0;     ///< landmarks added for cells that no other node sees (donut case)
};
/// Builds the graph (robot = node 0 at robot_cell), runs Dijkstra and fills the cost map. Cells of
/// the robot's accessible component that no node sees get coverage landmarks: the cheapest
/// reached cell next to them becomes a node, repeated until the component is covered (or
/// max_coverage_landmarks), so a donut-shaped floor with no anchor seeing a cell still works.
/// `robot_pos` is in continuous cell coordinates and must lie in an accessible cell.
CostMap computeCostMap(const cv::Mat& accessible, const std::vector<Landmark>& landmarks,
                       const Eigen::Vector2d& robot_pos, double d_max_cells, int max_coverage_landmarks);

/// Knowledge map (thesis 5.4): each scan position adds 1 to every cell within k_r. CV_32F.
/// (knowledge_model "visibility": visibilityKnowledgeMap(), visibility.h.)
cv::Mat knowledgeMap(const GridGeometry& geometry, const std::vector<Eigen::Vector2d>& scan_positions, double k_r_m);

/// Evaluation b = 1/(k + k0) * 1/(c + c0) with c in metres, on reached cells not in `blacklist`
/// (CV_8U, may be empty); 0 elsewhere. CV_32F.
cv::Mat evaluationMap(const cv::Mat& knowledge, const cv::Mat& cost_cells, double resolution, double k0, double c0,
                      const cv::Mat& blacklist);
/// The cell with the largest b (first in raster order on ties) among the cells set in `candidates`
/// (CV_8U; empty = all); (-1, -1) if every candidate's b is 0.
cv::Point argmaxCell(const cv::Mat& evaluation, const cv::Mat& candidates = cv::Mat());

/// Path back through the predecessors, in continuous cell coordinates: robot node, landmarks, target
/// cell centre; with the node index of each waypoint (-1 for the target).
std::vector<std::pair<Eigen::Vector2d, int>> extractPath(const CostMap& cost_map, const cv::Point& target);
/// The cell of `allowed` (CV_8U) nearest to `target` (first in raster order on ties) whose squared
/// distance transform value `sq_dt` (CV_32S, squared cells) is at least clearance_cells^2, searched
/// within clearance_cells of the target; `target` itself when it has that clearance already or
/// no such cell is there (or clearance_cells <= 0).
cv::Point clearTarget(const cv::Mat& sq_dt, const cv::Mat& allowed, const cv::Point& target, double clearance_cells);

/// Frontier cells: unknown cells 4-adjacent to a floor cell. CV_8U 0/1. With min_unknown_cells > 1
/// not those of an unknown region (8-connected) whose bounding box is smaller than that in both
/// directions; with ignore_wall_base the floor neighbour must have no obstacle cell among its 8
/// neighbours.
cv::Mat frontierCells(const cv::Mat& states, double min_unknown_cells = 0.0, bool ignore_wall_base = false);
/// Frontier cells that no scan position within view_radius_m has in plain sight: every straight
/// line (4-connected cell traversal) from the scan's cell to the frontier cell crosses a cell that
/// is not floor, or passes beside an obstacle cell (8-neighbour), before reaching it; in the last 2
/// cells before it only obstacle cells block (a line at a grazing angle enters a straight frontier
/// early, and a frontier in a wall gap lies beside the wall). Cells of frontier pieces (8-connected) whose
/// bounding box is smaller than min_extent_cells in both directions are dropped. `frontier`: the
/// frontier cells to test (empty: frontierCells(states)). CV_8U 0/1.
cv::Mat occludedFrontier(const cv::Mat& states, const GridGeometry& geometry,
                         const std::vector<Eigen::Vector2d>& scan_positions, double view_radius_m,
                         double min_extent_cells = 0.0, const cv::Mat& frontier = cv::Mat());
/// Open cells (termination): reached cells (finite cost), not blacklisted, and either with
/// knowledge below knowledge_threshold and a frontier cell within frontier_distance_cells, or (when
/// `occluded` is given) with knowledge below occluded_knowledge and a cell of `occluded` (CV_8U
/// occluded frontier cells) within frontier_distance_cells. Exploration is complete when there is
/// none. `frontier`: the frontier cells (empty: frontierCells(states)). CV_8U 0/1.
cv::Mat openCells(const cv::Mat& states, const cv::Mat& cost_cells, const cv::Mat& knowledge, const cv::Mat& blacklist,
                  double knowledge_threshold, double frontier_distance_cells, const cv::Mat& occluded = cv::Mat(),
                  double occluded_knowledge = 0.0, const cv::Mat& frontier = cv::Mat());

// ---- the whole step -------------------------------------------------------------------------

/// What a planning step needs.
struct PlanInput {
  cv::Mat states;  ///< floor grid (CellState)
  GridGeometry geometry;
  std::vector<Eigen::Vector2d> scan_positions;                ///< map-frame positions of all past scans [m]
  Pose2D robot;                                               ///< current robot pose (map frame)
  std::vector<std::pair<Eigen::Vector2d, double>> blacklist;  ///< discs (centre [m], radius [m]) never chosen again
  /// Given: no new scan location; the target is the reached, not blacklisted cell nearest to this
  /// point [m] (e.g. the start, once exploration is complete), the path as usual. Termination and
  /// coverage are evaluated as always.
  std::optional<Eigen::Vector2d> goal;
};

/// Everything a planning step computed (all grids share `geometry`).
struct PlanResult {
  bool success = false;
  std::string message;
  GridGeometry geometry;
  Pose2D robot;
  cv::Point robot_cell{-1, -1};  ///< node 0: robot cell, or the accessible cell it was joined to
  bool robot_snapped = false;    ///< the robot was off the accessible floor and joined to robot_cell

  cv::Mat states, sq_dt, accessible, anchors, skeleton_unpruned, skeleton, knowledge, blacklist, evaluation, open;
  cv::Mat occluded_frontier;  ///< frontier cells no scan within k_r has in plain sight (CV_8U; empty when off)
  cv::Mat gain;  ///< target_score "gain": expected gain of the sampled candidates [m^2] (CV_32F; else empty)
  CostMap cost_map;

  // the plan
  std::vector<Eigen::Vector2d> path;  ///< map-frame waypoints [m], robot position first, target last
  std::vector<bool> scan_at;          ///< per waypoint: scan there (intermediate landmarks and target)
  /// Per waypoint: the clearance of the leg that ends there (the first: of the robot's own cell), the
  /// smallest distance from it to anything that is not known floor (obstacles, contacts, unknown)
  /// [m] (legClearance). What the robot may be off its estimate and still pass.
  std::vector<double> clearance_m;
  cv::Point target_cell{-1, -1};
  Eigen::Vector2d target = Eigen::Vector2d::Zero();
  double score = 0.0;            ///< b at the target (the argmax, before a target_clearance_m move)
  double target_gain_m2 = -1.0;  ///< the chosen candidate's expected gain [m^2] (-1: not chosen by gain)
  double target_moved_m = 0.0;   ///< how far target_clearance_m moved the target from the argmax [m]
  double target_cost_m = 0.0;    ///< travel distance to the target [m]

  // termination and statistics
  bool complete = false;
  std::string complete_reason;
  size_t open_cells = 0;
  size_t open_cells_ignored = 0;  ///< open cells in pieces smaller than min_open_area_m2
  size_t open_beyond_reach = 0;   ///< open cells from views beyond reach (beyond_reach_min_m2)
  double coverage = 0.0;          ///< reached cells with knowledge >= threshold / reached cells
  double floor_area_m2 = 0.0;
  double accessible_area_m2 = 0.0;
  double reachable_area_m2 = 0.0;
  /// Accessible floor that lacks knowledge within frontier_distance_m of a frontier but that no path
  /// from the robot reaches [m^2]: unexplored space cut off in the floor map (a door the map shows
  /// too narrow for the robot, or closed by map error). Named in complete_reason from 0.5 m^2 on
  /// (the band of accessible floor within frontier_distance_m along about 2.5 m of frontier).
  double cut_off_area_m2 = 0.0;
  std::vector<std::pair<std::string, double>> timings_ms;  ///< per stage
};

/// Runs every stage up to the cost and knowledge maps (no target yet).
PlanResult computeMaps(const PlanInput& input, const PlannerConfig& config);
/// Evaluation, termination, target and path on the maps of `result` with the input's blacklist.
/// The target is the argmax of b among the reached cells that lack knowledge (k <
/// knowledge_threshold; Algorithm 5 line 10: "low knowledge and low cost") or are open (next to an
/// occluded frontier): so every scan removes candidates and the robot never dithers between
/// already scanned spots. With input.goal the target is the reached cell nearest to it instead.
void choosePlan(PlanResult& result, const PlanInput& input, const PlannerConfig& config);
/// computeMaps + choosePlan.
PlanResult planStep(const PlanInput& input, const PlannerConfig& config);

/// The smallest distance from the segment a-b (map frame) to a cell that is not floor, less a cell
/// (the surface may lie anywhere in its cell, the leg anywhere in the cells it crosses: never more
/// than the true distance) [m], from the squared distance transform of the floor (cells^2); 0 where
/// the segment leaves the floor or the grid.
double legClearance(const cv::Mat& sq_dt, const GridGeometry& geometry, const Eigen::Vector2d& a,
                    const Eigen::Vector2d& b);

/// Rasterises blacklist discs on a grid. CV_8U 0/1.
cv::Mat rasterizeDiscs(const GridGeometry& geometry, const std::vector<std::pair<Eigen::Vector2d, double>>& discs);

}  // namespace explorer
}  // namespace scanstop
