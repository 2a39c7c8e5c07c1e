#include "scanstop_slam/pose_graph.h"

#include <ceres/ceres.h>

#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>

#include "scanstop_common/config.h"

namespace scanstop {
namespace slam {
namespace {

/// Wraps an angle to [-pi, pi) for doubles and Ceres jets alike (derivative 1 everywhere).
template <typename T>
T wrapAngle(const T& a) {
  using std::floor;
  const T two_pi = T(2.0 * M_PI);
  return a - two_pi * floor((a + T(M_PI)) / two_pi);
}

/// The whitened residual sqrt_information * e of one edge (see pose_graph.h).
struct EdgeResidual {
  EdgeResidual(const Pose2D& z, const Eigen::Matrix3d& sqrt_information) : z_(z), sqrt_info_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* const pi, const T* const pj, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(pi[2]), s = sin(pi[2]);
    const T dx = pj[0] - pi[0], dy = pj[1] - pi[1];
    Eigen::Matrix<T, 3, 1> e;
    e(0) = c * dx + s * dy - T(z_.x);
    e(1) = -s * dx + c * dy - T(z_.y);
    e(2) = wrapAngle(pj[2] - pi[2] - T(z_.yaw));
    const Eigen::Matrix<T, 3, 1> w = sqrt_info_.cast<T>() * e;
    residual[0] = w(0);
    residual[1] = w(1);
    residual[2] = w(2);
    return true;
  }

  Pose2D z_;
  Eigen::Matrix3d sqrt_info_;
};

/// Upper factor U with U^T U = information (so |U e|^2 = e^T I e).
Eigen::Matrix3d sqrtInformation(const Eigen::Matrix3d& information) {
  return Eigen::LLT<Eigen::Matrix3d>(information).matrixU();
}

/// rho(s) of the configured loss for a squared whitened residual s (ceres' convention).
double robustCost(const PoseGraphConfig& config, double s) {
  const double a = config.loss_scale, a2 = a * a;
  if (config.loss == "huber") return s <= a2 ? s : 2.0 * a * std::sqrt(s) - a2;
  if (config.loss == "cauchy") return a2 * std::log1p(s / a2);
  return s;
}

size_t findRoot(std::vector<size_t>& parent, size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

void PoseGraphConfig::validate() const {
  requireOneOf("loss", loss, {"cauchy", "huber", "none"});
  requireInRange("loss_scale", loss_scale, 1e-9, 1e6);
  requireInRange("max_iterations", max_iterations, 1, 10000);
  requireInRange("function_tolerance", function_tolerance, 1e-20, 0.999);
}

size_t PoseGraph::addNode(const Pose2D& pose) {
  if (!pose.isFinite()) throw std::invalid_argument("pose graph: node pose " + pose.toString() + " is not finite");
  poses_.push_back(pose);
  fixed_.push_back(false);
  return poses_.size() - 1;
}

void PoseGraph::setPose(size_t node, const Pose2D& pose) {
  if (node >= poses_.size()) throw std::invalid_argument("pose graph: no node " + std::to_string(node));
  if (!pose.isFinite()) throw std::invalid_argument("pose graph: node pose " + pose.toString() + " is not finite");
  poses_[node] = pose;
}

void PoseGraph::setFixed(size_t node, bool fixed) {
  if (node >= poses_.size()) throw std::invalid_argument("pose graph: no node " + std::to_string(node));
  fixed_[node] = fixed;
}

void PoseGraph::addEdge(const PoseGraphEdge& edge) {
  const std::string name = "pose graph: edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to);
  if (edge.from >= poses_.size() || edge.to >= poses_.size())
    throw std::invalid_argument(name + ": unknown node (graph of " + std::to_string(poses_.size()) + ")");
  if (edge.from == edge.to) throw std::invalid_argument(name + ": joins a node to itself");
  if (!edge.T_from_to.isFinite()) throw std::invalid_argument(name + ": measurement is not finite");
  const Eigen::Matrix3d& I = edge.information;
  if (!I.allFinite() || (I - I.transpose()).norm() > 1e-9 * std::max(1.0, I.norm()) ||
      Eigen::LLT<Eigen::Matrix3d>(I).info() != Eigen::Success || I.determinant() <= 0.0)
    throw std::invalid_argument(name + ": information matrix is not finite, symmetric and positive definite");
  edges_.push_back(edge);
}

double PoseGraph::cost(const PoseGraphConfig& config) const {
  double total = 0.0;
  for (const PoseGraphEdge& e : edges_) {
    const Pose2D& pi = poses_[e.from];
    const Pose2D& pj = poses_[e.to];
    const double a[3] = {pi.x, pi.y, pi.yaw}, b[3] = {pj.x, pj.y, pj.yaw};
    double r[3];
    EdgeResidual(e.T_from_to, sqrtInformation(e.information))(a, b, r);
    const double s = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    total += 0.5 * (e.robust ? robustCost(config, s) : s);
  }
  return total;
}

PoseGraphSummary PoseGraph::optimize(const PoseGraphConfig& config) {
  config.validate();
  const auto start = std::chrono::steady_clock::now();
  PoseGraphSummary out;
  if (poses_.size() < 2 || edges_.empty()) {
    out.solved = true;
    out.message =
        "nothing to relax (" + std::to_string(poses_.size()) + " nodes, " + std::to_string(edges_.size()) + " edges)";
    return out;
  }
  // Work on a copy: a failed solve leaves the poses as they were.
  std::vector<std::array<double, 3>> x(poses_.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = {poses_[i].x, poses_[i].y, poses_[i].yaw};
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::vector<size_t> parent(x.size());
  std::iota(parent.begin(), parent.end(), size_t{0});
  for (const PoseGraphEdge& e : edges_) {
    ceres::CostFunction* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 3, 3, 3>(
        new EdgeResidual(e.T_from_to, sqrtInformation(e.information)));
    ceres::LossFunction* loss = nullptr;
    if (e.robust && config.loss == "cauchy") loss = new ceres::CauchyLoss(config.loss_scale);
    if (e.robust && config.loss == "huber") loss = new ceres::HuberLoss(config.loss_scale);
    problem.AddResidualBlock(cost, loss, x[e.from].data(), x[e.to].data());
    const size_t a = findRoot(parent, e.from), b = findRoot(parent, e.to);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is a component's lowest node
  }
  // Gauge: node 0 and setFixed() nodes are fixed; so is the lowest node of every component that
  // holds no fixed node.
  std::vector<bool> anchored(x.size(), false);
  for (size_t i = 0; i < x.size(); ++i)
    if (problem.HasParameterBlock(x[i].data()) && fixed(i)) anchored[findRoot(parent, i)] = true;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!problem.HasParameterBlock(x[i].data())) continue;
    if (fixed(i) || (findRoot(parent, i) == i && !anchored[i])) problem.SetParameterBlockConstant(x[i].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config.max_iterations;
  options.function_tolerance = config.function_tolerance;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-14;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.initial_cost = summary.initial_cost;
  out.final_cost = summary.final_cost;
  out.message = summary.BriefReport();
  out.solved = summary.IsSolutionUsable() && summary.final_cost <= summary.initial_cost;
  bool finite = true;
  std::vector<Pose2D> solution(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    solution[i] = Pose2D(x[i][0], x[i][1], normalizeAngle(x[i][2]));
    finite = finite && solution[i].isFinite();
  }
  out.solved = out.solved && finite;
  if (out.solved) {
    for (size_t i = 0; i < x.size(); ++i) {
      const double dm = std::hypot(solution[i].x - poses_[i].x, solution[i].y - poses_[i].y);
      const double dr = std::abs(normalizeAngle(solution[i].yaw - poses_[i].yaw));
      if (dm > 1e-9 || dr > 1e-9) ++out.moved;
      out.max_moved_m = std::max(out.max_moved_m, dm);
      out.max_moved_rad = std::max(out.max_moved_rad, dr);
    }
    poses_ = solution;
  }
  out.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace slam
}  // namespace scanstop
