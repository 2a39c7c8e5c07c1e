#pragma once
/// A 2D pose graph (x, y, yaw per scan) and its global relaxation, in the spirit of Lu-Milios /
/// 3DTK slam6D (Borrmann et al. 2008): nodes are the scans' poses in the map frame, edges are
/// relative pose measurements between two scans (from pairwise registration), each with a 3x3
/// information matrix. optimize() moves all poses but the first (the gauge, held fixed) to the
/// least-squares fit of all edges; loop edges (flagged robust) pass through a robust loss so a
/// single wrong one cannot drag the graph far. Solved with Ceres (sparse Cholesky, Levenberg-
/// Marquardt); the yaw error of every edge is normalized to (-pi, pi]. ROS-free.
///
/// Edge residual (frame of the edge's first node i, measurement z = T_i_j):
///   e = [ R(yaw_i)^T (t_j - t_i) - t_z ;  normalizeAngle(yaw_j - yaw_i - yaw_z) ]
/// and the cost of an edge is 0.5 * rho(e^T * information * e) (rho = identity for non-robust edges).

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "scanstop_common/pose.h"

namespace scanstop {
namespace slam {

/// One relative pose measurement between two nodes.
struct PoseGraphEdge {
  size_t from = 0;   ///< node i
  size_t to = 0;     ///< node j (!= i)
  Pose2D T_from_to;  ///< measured pose of node j in node i's frame [m, m, rad]
  /// Inverse covariance of (x, y, yaw) of T_from_to, in node i's frame [1/m^2, 1/(m rad), 1/rad^2];
  /// symmetric positive definite.
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
  bool robust = false;  ///< loop edge: passes through PoseGraphConfig's robust loss
};

/// How optimize() solves the graph.
struct PoseGraphConfig {
  /// Robust loss of robust (loop) edges: "cauchy", "huber" or "none" (plain least squares).
  std::string loss = "cauchy";
  /// Scale of the robust loss on the whitened residual sqrt(e^T I e): residuals below about this
  /// many standard deviations count fully, larger ones less and less [sigma, dimensionless], (0, 1e6].
  double loss_scale = 3.0;
  int max_iterations = 100;  ///< Levenberg-Marquardt iterations, [1, 10000]
  /// Convergence: relative cost change per iteration [dimensionless], (0, 1)
  double function_tolerance = 1e-12;
  void validate() const;
};

/// What optimize() did.
struct PoseGraphSummary {
  bool solved = false;  ///< the solver ran and reported a usable solution (false: poses unchanged)
  std::string message;  ///< the solver's report (why not, when !solved)
  int iterations = 0;
  double initial_cost = 0.0;   ///< 0.5 * sum of (robustified) squared whitened residuals, before
  double final_cost = 0.0;     ///< ... and after
  size_t moved = 0;            ///< nodes that moved by more than 1e-9 m or rad
  double max_moved_m = 0.0;    ///< largest position change of a node [m]
  double max_moved_rad = 0.0;  ///< largest yaw change of a node [rad]
  double time_s = 0.0;         ///< solver wall time [s]
};

class PoseGraph {
 public:
  /// Adds a node at an initial pose; returns its index (0, 1, ...). Node 0 is the gauge (fixed).
  size_t addNode(const Pose2D& pose);
  /// Throws std::invalid_argument for an unknown node, from == to, a non-finite measurement or an
  /// information matrix that is not finite, symmetric and positive definite.
  void addEdge(const PoseGraphEdge& edge);
  /// Sets a node's current pose (the start of the next optimize()).
  void setPose(size_t node, const Pose2D& pose);
  /// Holds a node where it is in optimize() (node 0 always is); e.g. poses of an earlier session
  /// whose edges are not known.
  void setFixed(size_t node, bool fixed = true);
  bool fixed(size_t node) const { return node == 0 || (node < fixed_.size() && fixed_[node]); }

  size_t size() const { return poses_.size(); }
  const std::vector<Pose2D>& poses() const { return poses_; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }
  /// The cost of the current poses as optimize() counts it (robust loss on robust edges).
  double cost(const PoseGraphConfig& config) const;

  /// Relaxes the graph: all nodes but node 0 and setFixed() ones move to the minimum of the edges' cost, yaw
  /// normalized to (-pi, pi]. Nodes without any edge path to node 0 keep their relative layout only
  /// as far as their edges say (a node without edges does not move). Fewer than two nodes or no
  /// edge: nothing to do (solved = true, nothing moved).
  PoseGraphSummary optimize(const PoseGraphConfig& config = PoseGraphConfig());

 private:
  std::vector<Pose2D> poses_;
  std::vector<bool> fixed_;
  std::vector<PoseGraphEdge> edges_;
};

}  // namespace slam
}  // namespace scanstop
