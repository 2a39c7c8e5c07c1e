#include "scanstop_slam/icp_slam.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "scanstop_common/config.h"

namespace scanstop {
namespace slam {

void SlamConfig::validate() const {
  icp.validate();
  requireInRange("coarse_c_max_m", coarse_c_max_m, 0.0, 5.0, "m");
  requireInRange("source_voxel_m", source_voxel_m, 0.0, 1.0, "m");
  requireInRange("refine_t_c_m", refine_t_c_m, 0.0, 0.01, "m");
  requireInRange("refine_r_c_rad", refine_r_c_rad, 1e-9, 0.01, "rad");
  requireInRange("refine_max_iterations", refine_max_iterations, 1, 10000);
  requireInRange("refine_source_voxel_m", refine_source_voxel_m, 0.0, 1.0, "m");
  requireInRange("refine_max_correction_m", refine_max_correction_m, 0.0, 10.0, "m");
  requireInRange("refine_max_correction_rad", refine_max_correction_rad, 0.0, M_PI, "rad");
  requireInRange("max_points_per_voxel", max_points_per_voxel, 1, 100000);
  requireInRange("map_spacing_m", map_spacing_m, 0.0, icp.c_max_m, "m");
  requireInRange("odom_scale_min_travel_m", odom_scale_min_travel_m, 0.01, 100.0, "m");
  requireInRange("odom_turn_min_total_rad", odom_turn_min_total_rad, 0.0, 1000.0, "rad");
  requireInRange("prior_sigma_m", prior_sigma_m, 1e-6, 10.0, "m");
  requireInRange("prior_sigma_per_m", prior_sigma_per_m, 0.0, 1.0);
  requireInRange("prior_sigma_rad", prior_sigma_rad, 1e-6, M_PI, "rad");
  requireInRange("prior_sigma_rad_per_rad", prior_sigma_rad_per_rad, 0.0, 1.0);
  requireInRange("prior_sigma_rad_per_m", prior_sigma_rad_per_m, 0.0, 1.0, "rad/m");
  requireInRange("prior_gate", prior_gate, 1e-6, 1e6);
  requireInRange("odometry_gate", odometry_gate, 0.0, 1e6);
  requireInRange("odometry_gate_rms_ratio", odometry_gate_rms_ratio, 1.0, 100.0);
  requireInRange("odometry_gate_weak_rms_ratio", odometry_gate_weak_rms_ratio, 1.0, 100.0);
  requireInRange("failure_retry_degeneracy_ratio", failure_retry_degeneracy_ratio, 0.0, 1.0);
  requireInRange("max_point_distance_m", max_point_distance_m, 0.1, 10000.0, "m");
  requireInRange("max_odom_jump_m", max_odom_jump_m, 0.01, 100000.0, "m");
  requireInRange("relax_neighbours", relax_neighbours, 0, 100);
  requireInRange("relax_loop_candidates", relax_loop_candidates, 0, 100);
  requireInRange("relax_loop_min_gap", relax_loop_min_gap, 2, 100000);
  requireInRange("relax_max_distance_m", relax_max_distance_m, 1e-6, 1000.0, "m");
  requireInRange("relax_voxel_m", relax_voxel_m, 0.01, 1.0, "m");
  requireInRange("relax_min_overlap", relax_min_overlap, 0.0, 1.0);
  requireInRange("relax_max_rms_m", relax_max_rms_m, 1e-6, 1.0, "m");
  requireInRange("relax_update_m", relax_update_m, 0.0, 10.0, "m");
  requireInRange("relax_update_rad", relax_update_rad, 0.0, M_PI, "rad");
  graph.validate();
}

Eigen::Matrix3d pairwiseInformation(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source,
                                    const Eigen::Isometry3d& T_target_source, const IcpConfig& config) {
  constexpr double kEffectivePoints = 50.0;
  constexpr double kMinSigma = 0.005;  // [m]
  const bool skip_horizontal = !config.six_dof && config.ignore_horizontal;
  const Eigen::Isometry3f T = T_target_source.cast<float>();
  const Eigen::Vector2d t = T_target_source.translation().head<2>();
  Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
  double sum_r2 = 0.0;
  size_t n = 0;
  for (const Eigen::Vector3f& p : source) {
    const Eigen::Vector3f q = T * p;
    Eigen::Vector3f m;
    float d2 = 0.0f;
    bool horizontal = false;
    Surface surface;
    if (!target.nearest(q, config.c_max_m, m, d2, &horizontal, &surface) || !surface.planar) continue;
    if (skip_horizontal && horizontal) continue;
    const Eigen::Vector3d nrm = surface.normal.cast<double>();
    const Eigen::Vector2d v = q.head<2>().cast<double>() - t;  // R p: d(T p)/d yaw = z x (R p)
    const Eigen::Vector3d J(nrm.x(), nrm.y(), nrm.x() * -v.y() + nrm.y() * v.x());
    JtJ += J * J.transpose();
    const double r = nrm.dot((q - m).cast<double>());
    sum_r2 += r * r;
    ++n;
  }
  Eigen::Matrix3d info = Eigen::Matrix3d::Identity();
  if (n == 0) return info;
  const double sigma = std::max(kMinSigma, std::sqrt(sum_r2 / n));
  info += JtJ / static_cast<double>(n) * (kEffectivePoints / (sigma * sigma));
  return 0.5 * (info + info.transpose());
}

std::string scanProblem(const PointCloud& scan_base, double max_point_distance_m) {
  if (scan_base.empty()) return "the cloud has no points";
  size_t finite = 0;
  for (size_t i = 0; i < scan_base.points.size(); ++i) {
    const Eigen::Vector3f& p = scan_base.points[i];
    if (p.hasNaN()) continue;  // NaN marks a beam without a return
    std::ostringstream where;
    where << "point " << i << " (" << p.x() << ", " << p.y() << ", " << p.z() << ")";
    if (!p.allFinite()) return where.str() + " has an infinite coordinate";
    if (p.cast<double>().norm() > max_point_distance_m)
      return where.str() + " is " + std::to_string(p.norm()) + " m from base_link, beyond max_point_distance_m " +
             std::to_string(max_point_distance_m) + " m";
    ++finite;
  }
  if (finite == 0) return "the cloud has no finite point (all " + std::to_string(scan_base.size()) + " are NaN)";
  return "";
}

IcpSlam::IcpSlam(const SlamConfig& config, const std::string& map_dir)
    : config_(config),
      map_((config.validate(), config.icp.c_max_m), config.max_points_per_voxel, config.map_spacing_m) {
  if (map_dir.empty()) return;
  dir_ = std::make_unique<MapDirectory>(map_dir);
  for (const MapProblem& p : dir_->problems()) skipped_.push_back({p.path, p.problem});
  // Resume: the earlier session's graph edges are not stored, so its poses stay as they are (fixed
  // nodes); new scans relax against them.
  for (size_t i = 0; i < dir_->size(); ++i) {
    const MapScanInfo& info = dir_->scans()[i];
    // The pose is kept either way (the trajectory goes on from the last scan).
    last_map_ = info.map_pose;
    last_odom_ = info.odom_pose;
    PointCloud scan;
    try {
      scan = dir_->loadScan(i);
    } catch (const std::exception& e) {
      skipped_.push_back({dir_->dir() + "/" + info.file, e.what()});
      continue;
    }
    const std::string problem = scanProblem(scan, config_.max_point_distance_m);
    if (!problem.empty()) {
      skipped_.push_back({dir_->dir() + "/" + info.file, "scan " + std::to_string(info.index) + ": " + problem});
      continue;
    }
    const Eigen::Vector3f origin = info.map_pose.toIsometry3f() * info.sensor_origin.cast<float>();
    map_.add(transformCloud(scan, info.map_pose.toIsometry3f()).points, &origin);
    KeptScan k;
    k.index = info.index;
    k.stamp_s = info.stamp_s;
    k.pose = info.map_pose;
    k.origin = info.sensor_origin.cast<float>();
    k.odom = info.odom_pose;
    k.scale_evidence = info.converged;
    if (config_.relax) k.points = sample(scan.points, config_.relax_voxel_m);
    kept_.push_back(std::move(k));
    graph_.setFixed(graph_.addNode(info.map_pose));
  }
  count_ = static_cast<size_t>(dir_->nextIndex());
}

std::vector<ScanPose> IcpSlam::poses() const {
  std::vector<ScanPose> out;
  out.reserve(kept_.size());
  for (const KeptScan& k : kept_) out.push_back({k.index, k.stamp_s, k.pose});
  return out;
}

Eigen::MatrixXd IcpSlam::priorInformation(const Pose2D& odom_leg) const {
  const double d = std::hypot(odom_leg.x, odom_leg.y), turn = std::abs(normalizeAngle(odom_leg.yaw));
  const double s_m = std::hypot(config_.prior_sigma_m, config_.prior_sigma_per_m * d);
  const double s_rad =
      std::sqrt(config_.prior_sigma_rad * config_.prior_sigma_rad +
                std::pow(config_.prior_sigma_rad_per_rad * turn, 2) + std::pow(config_.prior_sigma_rad_per_m * d, 2));
  const double i_m = 1.0 / (s_m * s_m), i_rad = 1.0 / (s_rad * s_rad);
  if (!config_.icp.six_dof) return Eigen::Vector3d(i_m, i_m, i_rad).asDiagonal();
  const double i_z = 1.0 / (config_.prior_sigma_m * config_.prior_sigma_m);
  const double i_tilt = 1.0 / (config_.prior_sigma_rad * config_.prior_sigma_rad);
  Eigen::VectorXd diag(6);
  diag << i_m, i_m, i_z, i_tilt, i_tilt, i_rad;
  return diag.asDiagonal();
}

IcpResult IcpSlam::registerStages(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source,
                                  const Eigen::Isometry3d& start, const Eigen::Vector3f& origin, Registration* r,
                                  const Eigen::MatrixXd* prior_information, bool coarse_stage,
                                  const IcpConfig* icp_config) const {
  const IcpConfig& base = icp_config ? *icp_config : config_.icp;
  Eigen::Isometry3d from = start;
  int coarse_iterations = 0;
  if (coarse_stage && config_.coarse_c_max_m > base.c_max_m) {
    // The coarse stage only moves the start; its own checks use the coarse distance.
    IcpConfig coarse = base;
    coarse.c_max_m = config_.coarse_c_max_m;
    if (config_.coarse_point_to_point) coarse.method = IcpMethod::point_to_point;
    coarse.t_c_m = std::max(coarse.t_c_m, 0.002);
    coarse.r_c_rad = std::max(coarse.r_c_rad, 0.1 * M_PI / 180.0);
    const IcpResult c = icp(target, coarseSource(source), from, coarse, &origin, nullptr, prior_information);
    coarse_iterations = c.iterations;
    if (c.converged) from = c.T_target_source;
  }
  // Every stage after the coarse one keeps the initial guess (the odometry prior), not the coarse
  // stage's result, along the weak directions of its own final pairs: the coarse stage's far pairs
  // must not slide a scan along a corridor (office_loop seed 1 scan 121: 4 cm off from odometry,
  // 16 cm after a coarse slide the fine pairs could not see).
  IcpResult result = icp(target, source, from, base, &origin, &start, prior_information);
  result.iterations += coarse_iterations;
  if (result.converged && config_.refine_t_c_m > 0.0) {
    IcpConfig refine = base;
    refine.unique_matches = true;
    refine.t_c_m = config_.refine_t_c_m;
    refine.r_c_rad = config_.refine_r_c_rad;
    refine.max_iterations = config_.refine_max_iterations;
    IcpResult refined =
        icp(target, refineSource(source), result.T_target_source, refine, &origin, &start, prior_information);
    // Not settled within its iterations, or moved farther than a bias can be: the thesis stage's
    // result stands.
    const Eigen::Isometry3d moved = result.T_target_source.inverse() * refined.T_target_source;
    const double moved_m = moved.translation().norm(), moved_rad = Eigen::AngleAxisd(moved.linear()).angle();
    const bool rejected = refined.converged &&
                          (moved_m > config_.refine_max_correction_m || moved_rad > config_.refine_max_correction_rad);
    if (r) {
      r->refine_moved_m = moved_m;
      r->refine_moved_rad = moved_rad;
      r->refine_rejected = rejected;
    }
    if (refined.converged && !rejected) {
      refined.iterations += result.iterations;
      result = refined;
    } else {
      result.iterations += refined.iterations;
    }
  }
  if (result.converged) {
    // The bound on the correction applies to the whole correction of the initial guess.
    const Eigen::Isometry3d correction = start.inverse() * result.T_target_source;
    if (correction.translation().norm() > base.max_correction_m ||
        Eigen::AngleAxisd(correction.linear()).angle() > base.max_correction_rad) {
      result.converged = false;
      result.failure = "the correction of the initial guess (" + std::to_string(correction.translation().norm()) +
                       " m) exceeds max_correction";
    }
  }
  return result;
}

void IcpSlam::registerInto(const VoxelMap& target, const PointCloud& scan_base, const Eigen::Vector3f& origin,
                           Registration& r) const {
  const std::vector<Eigen::Vector3f> source = sample(scan_base.points, config_.source_voxel_m);
  const Eigen::Isometry3d start = r.guess.toIsometry3d();
  const Eigen::MatrixXd prior_information = priorInformation(r.odom_leg);
  const Eigen::MatrixXd* prior = config_.odometry_prior ? &prior_information : nullptr;
  IcpResult icp_result = registerStages(target, source, start, origin, &r, prior);
  if (config_.odometry_prior && icp_result.converged) {
    r.prior_distance = guessDistance(r.guess, Pose2D::fromIsometry3d(icp_result.T_target_source), prior_information);
    // Only where the prior had a say (some stage had weak directions); elsewhere a second run is the same.
    if (r.prior_distance > config_.prior_gate && icp_result.remapped) {
      r.prior_rejected = true;
      icp_result = registerStages(target, source, start, origin, &r, nullptr);
      prior = nullptr;
    }
  }
  if (config_.odometry_gate > 0.0 && icp_result.converged) {
    r.guess_distance = guessDistance(r.guess, Pose2D::fromIsometry3d(icp_result.T_target_source), prior_information);
    if (r.guess_distance > config_.odometry_gate) {
      r.gate_retried = true;
      // A later result stands when it converged within the gate at an rms of at most ratio times the first's.
      const auto stands = [&](const IcpResult& later, double ratio) {
        return later.converged && later.rms_m <= ratio * icp_result.rms_m &&
               guessDistance(r.guess, Pose2D::fromIsometry3d(later.T_target_source), prior_information) <=
                   config_.odometry_gate;
      };
      const auto replace = [&](const Registration& later_r, const IcpResult& later, bool widened) {
        const double first_distance = r.guess_distance;
        r = later_r;
        r.gate_retried = true;
        r.gate_replaced = true;
        r.gate_widened = widened;
        r.guess_distance = first_distance;
        icp_result = later;
      };
      Registration second = r;
      const IcpResult retry = registerStages(target, source, start, origin, &second, prior, false);
      if (stands(retry, config_.odometry_gate_rms_ratio)) {
        replace(second, retry, false);
      } else if (config_.failure_retry_degeneracy_ratio > config_.icp.degeneracy_ratio) {
        // Neither result lies within the gate: the scan may have slid along a direction the pairs
        // hold too weakly to be counted weak at degeneracy_ratio (office_large seed 1, scan 88 in
        // the 48 m hall: condition 95, 27.6 cm from a guess 2 cm off, also against the map at the
        // true poses, with a 12 % lower rms). Registered once more with more directions counted
        // weak (kept at the guess), as a failed registration is; that result stands when it lies
        // within the gate and fits the map as well, or, when the first result's own condition
        // counts as weak at that ratio, nearly as well (odometry_gate_weak_rms_ratio: a slide along
        // a weakly held direction fits a little better than the truth; a guess that is truly off
        // fits much worse when held there: office_loop seed 1 scan 61, 1.48 times the rms).
        IcpConfig wider = config_.icp;
        wider.degeneracy_ratio = config_.failure_retry_degeneracy_ratio;
        Registration third = r;
        const IcpResult held = registerStages(target, source, start, origin, &third, prior, true, &wider);
        const bool weakly_held = icp_result.condition * config_.failure_retry_degeneracy_ratio > 1.0;
        if (stands(held, weakly_held ? std::max(config_.odometry_gate_rms_ratio, config_.odometry_gate_weak_rms_ratio)
                                     : config_.odometry_gate_rms_ratio))
          replace(third, held, true);
      }
    }
  }
  // A failed registration (no convergence, or a correction beyond the bound) keeps the odometry
  // pose, and every later scan inherits its error. Registered again with more directions counted
  // weak (kept at the guess), it often converges: furnished_1 seed 2 scan 2 crept 2.5 m along a
  // weakly held direction (condition 28) and failed, kept 6.6 cm off; with degeneracy_ratio 0.05
  // 1.9 cm. The second result stands when it converges within the odometry gate.
  if (!icp_result.converged && config_.failure_retry_degeneracy_ratio > config_.icp.degeneracy_ratio) {
    IcpConfig wider = config_.icp;
    wider.degeneracy_ratio = config_.failure_retry_degeneracy_ratio;
    Registration second = r;
    const IcpResult retry = registerStages(target, source, start, origin, &second, prior, true, &wider);
    r.failure_retried = true;
    r.first_failure = icp_result.failure;
    const bool within = config_.odometry_gate <= 0.0 ||
                        guessDistance(r.guess, Pose2D::fromIsometry3d(retry.T_target_source), prior_information) <=
                            config_.odometry_gate;
    if (retry.converged && within) {
      const std::string first = r.first_failure;
      r = second;
      r.failure_retried = true;
      r.failure_replaced = true;
      r.first_failure = first;
      icp_result = retry;
    }
  }
  r.weak_gain_m = icp_result.weak_gain_m;
  r.weak_gain_rad = icp_result.weak_gain_rad;
  r.converged = icp_result.converged;
  r.failure = icp_result.failure;
  r.iterations = icp_result.iterations;
  r.correspondences = icp_result.correspondences;
  r.rms_m = icp_result.rms_m;
  r.overlap = icp_result.overlap;
  r.condition = icp_result.condition;
  r.degenerate = icp_result.degenerate;
  r.weak_direction = icp_result.weak_direction;
  r.remapped = icp_result.remapped;
  r.map_pose = r.converged ? Pose2D::fromIsometry3d(icp_result.T_target_source) : r.guess;
}

double IcpSlam::guessDistance(const Pose2D& guess, const Pose2D& result,
                              const Eigen::MatrixXd& prior_information) const {
  const Pose2D offset = guess.between(result);
  const Eigen::Vector3d d(offset.x, offset.y, offset.yaw);
  // x, y, yaw of the prior's information (6dof: rows and columns 0, 1, 5 of x, y, z, roll, pitch, yaw).
  const int k[3] = {0, 1, config_.icp.six_dof ? 5 : 2};
  Eigen::Matrix3d info;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) info(i, j) = prior_information(k[i], k[j]);
  return std::sqrt(d.dot(info * d));
}

Registration IcpSlam::registerAgainst(const VoxelMap& target, const PointCloud& scan_base, const Pose2D& guess,
                                      const Eigen::Vector3d& sensor_origin, const Pose2D& odom_leg) const {
  Registration r;
  r.guess = guess;
  r.odom_leg = odom_leg;
  const auto start = std::chrono::steady_clock::now();
  registerInto(target, scan_base, sensor_origin.cast<float>(), r);
  r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

void IcpSlam::addRelaxEdges(PoseGraph& graph, const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin,
                            Registration& r) const {
  const size_t j = graph.size() - 1;  // the new node
  const Pose2D& pj = graph.poses()[j];
  // Candidates: the previous node, the nearest others, the nearest loop candidates.
  std::vector<std::pair<double, size_t>> near, loops;
  for (size_t i = 0; i + 1 < j; ++i) {
    const double d = std::hypot(graph.poses()[i].x - pj.x, graph.poses()[i].y - pj.y);
    if (d > config_.relax_max_distance_m || kept_[i].points.empty()) continue;
    const bool loop = static_cast<long>(r.index) - static_cast<long>(kept_[i].index) >= config_.relax_loop_min_gap;
    (loop ? loops : near).push_back({d, i});
  }
  std::sort(near.begin(), near.end());
  std::sort(loops.begin(), loops.end());
  std::vector<size_t> candidates;
  if (j >= 1 && config_.relax_neighbours > 0) candidates.push_back(j - 1);
  for (size_t k = 0; k < near.size() && static_cast<int>(candidates.size()) < config_.relax_neighbours; ++k)
    candidates.push_back(near[k].second);
  // Far-back scans that are among the nearest count as loop candidates too (a robust edge).
  const size_t before_loops = candidates.size();
  for (size_t k = 0;
       k < loops.size() && static_cast<int>(candidates.size() - before_loops) < config_.relax_loop_candidates; ++k)
    candidates.push_back(loops[k].second);
  bool previous_joined = false;
  for (const size_t i : candidates) {
    if (kept_[i].points.empty()) continue;  // e.g. a resumed scan without relax data
    ++r.relax_edges_tried;
    VoxelMap target(config_.icp.c_max_m, config_.max_points_per_voxel, config_.map_spacing_m);
    target.add(kept_[i].points, &kept_[i].origin);
    const Pose2D guess = graph.poses()[i].between(pj);
    const IcpResult pair = registerStages(target, points, guess.toIsometry3d(), origin, nullptr);
    if (!pair.converged || pair.overlap < config_.relax_min_overlap || pair.rms_m > config_.relax_max_rms_m) continue;
    PoseGraphEdge e;
    e.from = i;
    e.to = j;
    e.T_from_to = Pose2D::fromIsometry3d(pair.T_target_source);
    e.information = pairwiseInformation(target, points, pair.T_target_source, config_.icp);
    e.robust = static_cast<long>(r.index) - static_cast<long>(kept_[i].index) >= config_.relax_loop_min_gap;
    graph.addEdge(e);
    ++r.relax_edges;
    if (i + 1 == j) previous_joined = true;
  }
  if (j >= 1 && r.converged) {
    // The registration against the map, as an edge from the previous scan: the new scan's pose
    // relative to where the map holds the previous one, with the information of that registration
    // (the same stand-in as pairwise edges, over the map). Pairwise registrations of two sparse
    // scans alone are less accurate than against the map of all earlier scans.
    PoseGraphEdge e;
    e.from = j - 1;
    e.to = j;
    e.T_from_to = kept_[j - 1].pose.between(pj);
    e.information = pairwiseInformation(map_, points, pj.toIsometry3d(), config_.icp);
    graph.addEdge(e);
  } else if (!previous_joined && j >= 1) {
    // Keeps the chain joined: the relative pose as odometry (the registration failed) left it,
    // weakly (5 cm, 1 deg).
    PoseGraphEdge e;
    e.from = j - 1;
    e.to = j;
    e.T_from_to = kept_[j - 1].pose.between(pj);
    const double s_m = 0.05, s_rad = 1.0 * M_PI / 180.0;
    e.information = Eigen::Vector3d(1 / (s_m * s_m), 1 / (s_m * s_m), 1 / (s_rad * s_rad)).asDiagonal();
    graph.addEdge(e);
  }
}

void IcpSlam::rebuildMap() {
  map_ = VoxelMap(config_.icp.c_max_m, config_.max_points_per_voxel, config_.map_spacing_m);
  for (const KeptScan& k : kept_) {
    const Eigen::Isometry3f T = k.pose.toIsometry3f();
    const Eigen::Vector3f origin = T * k.origin;
    std::vector<Eigen::Vector3f> in_map;
    if (dir_) {
      // The full scan, as a resume would load it (kept_ holds only the scans that loaded).
      const auto& scans = dir_->scans();
      const auto it =
          std::find_if(scans.begin(), scans.end(), [&](const MapScanInfo& s) { return s.index == k.index; });
      if (it != scans.end()) {
        try {
          for (const auto& p : dir_->loadScan(static_cast<size_t>(it - scans.begin())).points)
            if (p.allFinite()) in_map.push_back(T * p);
        } catch (const std::exception&) {
          in_map.clear();
        }
      }
    }
    if (in_map.empty())
      for (const auto& p : k.points) in_map.push_back(T * p);
    map_.add(in_map, &origin);
  }
}

std::string IcpSlam::odomProblem(const Pose2D& odom_pose) const {
  if (!std::isfinite(odom_pose.x) || !std::isfinite(odom_pose.y) || !std::isfinite(odom_pose.yaw))
    return "the odometry pose " + odom_pose.toString() + " is not finite";
  if (count_ == 0) return "";
  const double jump = std::hypot(odom_pose.x - last_odom_.x, odom_pose.y - last_odom_.y);
  if (jump > config_.max_odom_jump_m)
    return "the odometry pose " + odom_pose.toString() + " is " + std::to_string(jump) + " m from the last scan's " +
           last_odom_.toString() + ", beyond max_odom_jump_m " + std::to_string(config_.max_odom_jump_m) +
           " m (an odometry reset or a corrupt pose)";
  return "";
}

bool IcpSlam::scaleEvidence(size_t i) const {
  return kept_[i].scale_evidence && (!config_.odom_scale_both_ends || kept_[i - 1].scale_evidence);
}

double IcpSlam::odomScale() const {
  // Least squares k = sum(l o) / sum(o^2): o the odometry's translation of a leg, l the registered
  // translation projected onto the odometry's direction.
  double lo = 0.0, oo = 0.0;
  int legs = 0;
  for (size_t i = 1; i < kept_.size(); ++i) {
    if (!scaleEvidence(i)) continue;
    const Pose2D o = kept_[i - 1].odom.between(kept_[i].odom);
    const double len = std::hypot(o.x, o.y);
    if (len < config_.odom_scale_min_travel_m) continue;
    const Pose2D m = kept_[i - 1].pose.between(kept_[i].pose);
    lo += (m.x * o.x + m.y * o.y);
    oo += len * len;
    ++legs;
  }
  if (legs < 2 || oo <= 0.0) return 1.0;
  return std::min(1.25, std::max(0.8, lo / oo));
}

std::pair<double, double> IcpSlam::odomTurn() const {
  // Least squares of m = k o + b over the legs: o the odometry's yaw change, m the registered one.
  double s_oo = 0.0, s_o = 0.0, s_mo = 0.0, s_m = 0.0, turned = 0.0;
  int legs = 0;
  for (size_t i = 1; i < kept_.size(); ++i) {
    if (!scaleEvidence(i)) continue;
    const Pose2D o = kept_[i - 1].odom.between(kept_[i].odom);
    if (std::hypot(o.x, o.y) < config_.odom_scale_min_travel_m) continue;
    const Pose2D m = kept_[i - 1].pose.between(kept_[i].pose);
    s_oo += o.yaw * o.yaw;
    s_o += o.yaw;
    s_mo += m.yaw * o.yaw;
    s_m += m.yaw;
    turned += std::abs(o.yaw);
    ++legs;
  }
  const double det = legs * s_oo - s_o * s_o;
  if (legs < 3 || turned < config_.odom_turn_min_total_rad || det <= 1e-9) return {1.0, 0.0};
  const double k = (legs * s_mo - s_o * s_m) / det;
  const double b = (s_m - k * s_o) / legs;
  const double b_max = 3.0 * M_PI / 180.0;
  return {std::min(1.1, std::max(0.9, k)), std::min(b_max, std::max(-b_max, b))};
}

std::vector<Eigen::Vector3f> IcpSlam::sample(const std::vector<Eigen::Vector3f>& points, double voxel_m) const {
  return config_.source_centroids ? voxelCentroids(points, voxel_m) : voxelDownsample(points, voxel_m);
}

std::vector<Eigen::Vector3f> IcpSlam::coarseSource(const std::vector<Eigen::Vector3f>& source) const {
  // A sparser subset is plenty for the coarse stage and keeps its wider search cheap.
  return sample(source, std::max(config_.source_voxel_m, 0.05));
}

std::vector<Eigen::Vector3f> IcpSlam::refineSource(const std::vector<Eigen::Vector3f>& source) const {
  return config_.refine_source_voxel_m > config_.source_voxel_m ? sample(source, config_.refine_source_voxel_m)
                                                                : source;
}

Registration IcpSlam::registerScan(const PointCloud& scan_base, const Pose2D& odom_pose,
                                   const Eigen::Vector3d& sensor_origin, double stamp_s) {
  const auto start = std::chrono::steady_clock::now();
  // Every check before anything changes: a refused scan leaves the map, the directory and the poses as they were.
  std::string problem = scanProblem(scan_base, config_.max_point_distance_m);
  if (problem.empty()) problem = odomProblem(odom_pose);
  if (problem.empty() && !sensor_origin.allFinite()) problem = "the sensor origin is not finite";
  if (problem.empty() && !std::isfinite(stamp_s)) problem = "the stamp is not finite";
  if (!problem.empty()) throw std::invalid_argument(problem);
  Registration r;
  r.index = static_cast<uint32_t>(dir_ ? static_cast<size_t>(dir_->nextIndex()) : count_);
  // Initial guess: the last corrected pose composed with the odometry delta since then. The first
  // scan defines the map: map = odom at the first scan.
  if (count_ == 0) {
    r.guess = odom_pose;
  } else {
    Pose2D delta = last_odom_.between(odom_pose);
    r.odom_scale = config_.odom_scale_estimation ? odomScale() : 1.0;
    delta.x *= r.odom_scale;
    delta.y *= r.odom_scale;
    if (config_.odom_turn_estimation) {
      std::tie(r.odom_turn_scale, r.odom_leg_turn_rad) = odomTurn();
      const bool leg = std::hypot(delta.x, delta.y) >= config_.odom_scale_min_travel_m;
      if (!leg) r.odom_leg_turn_rad = 0.0;
      // The robot turned (k - 1) * yaw more than the odometry says before it drove.
      const double extra = (r.odom_turn_scale - 1.0) * delta.yaw;
      const double c = std::cos(extra), s = std::sin(extra);
      delta = Pose2D(c * delta.x - s * delta.y, s * delta.x + c * delta.y,
                     normalizeAngle(r.odom_turn_scale * delta.yaw + r.odom_leg_turn_rad));
    }
    r.odom_leg = delta;
    r.guess = last_map_ * delta;
  }
  const Eigen::Vector3f origin = sensor_origin.cast<float>();
  if (map_.size() == 0) {  // the first scan (or every earlier one was skipped) defines the map
    r.map_pose = r.guess;
    r.converged = true;
  } else {
    registerInto(map_, scan_base, origin, r);
  }
  // Global relaxation: on a copy of the graph, so a scan that cannot be stored changes nothing.
  PoseGraph graph = graph_;
  std::vector<Eigen::Vector3f> kept_points;
  std::vector<std::pair<uint32_t, Pose2D>> updates;  // (scan index, corrected pose) to apply
  std::vector<size_t> update_nodes;
  if (config_.relax) {
    const auto relax_start = std::chrono::steady_clock::now();
    kept_points = sample(scan_base.points, config_.relax_voxel_m);
    graph.addNode(r.map_pose);
    try {
      addRelaxEdges(graph, kept_points, origin, r);
      const PoseGraphSummary g = graph.optimize(config_.graph);
      r.relax_solved = g.solved;
      if (!g.solved) r.relax_problem = "the pose graph was not solved: " + g.message;
    } catch (const std::exception& e) {
      r.relax_problem = std::string("relaxation failed: ") + e.what();
    }
    if (r.relax_solved) {
      r.map_pose = graph.poses().back();
      for (size_t i = 0; i < kept_.size(); ++i) {
        const Pose2D& p = graph.poses()[i];
        const double dm = std::hypot(p.x - kept_[i].pose.x, p.y - kept_[i].pose.y);
        const double dr = std::abs(normalizeAngle(p.yaw - kept_[i].pose.yaw));
        if (dm > config_.relax_update_m || dr > config_.relax_update_rad) r.relaxed = true;
      }
      if (r.relaxed)
        for (size_t i = 0; i < kept_.size(); ++i) {
          const Pose2D& p = graph.poses()[i];
          if (p.x == kept_[i].pose.x && p.y == kept_[i].pose.y && p.yaw == kept_[i].pose.yaw) continue;
          updates.push_back({kept_[i].index, p});
          update_nodes.push_back(i);
          r.relax_max_moved_m = std::max(r.relax_max_moved_m, std::hypot(p.x - kept_[i].pose.x, p.y - kept_[i].pose.y));
          r.relax_max_moved_rad = std::max(r.relax_max_moved_rad, std::abs(normalizeAngle(p.yaw - kept_[i].pose.yaw)));
        }
      r.relax_moved = updates.size();
    } else {
      // The graph keeps the node (its edges stay), at the registration's pose.
      graph = graph_;
      graph.addNode(r.map_pose);
    }
    r.relax_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - relax_start).count();
  }
  // The whole scan (not only the matching subset) joins the map.
  const Eigen::Isometry3f T_map_base = r.map_pose.toIsometry3f();
  std::vector<Eigen::Vector3f> in_map;
  in_map.reserve(scan_base.points.size());
  for (const auto& p : scan_base.points)
    if (p.allFinite()) in_map.push_back(T_map_base * p);
  if (dir_) {
    MapScanInfo info;
    info.index = r.index;
    info.stamp_s = stamp_s;
    info.map_pose = r.map_pose;
    info.odom_pose = odom_pose;
    info.sensor_origin = sensor_origin;
    info.converged = r.converged;
    info.iterations = static_cast<uint32_t>(r.iterations);
    info.correspondences = static_cast<uint32_t>(r.correspondences);
    info.rms_m = r.rms_m;
    info.overlap = r.overlap;
    dir_->append(info, scan_base);  // throws before the in-memory map changes: nothing half-applied
  }
  KeptScan k;
  k.index = r.index;
  k.stamp_s = stamp_s;
  k.pose = r.map_pose;
  k.points = std::move(kept_points);
  k.origin = origin;
  k.odom = odom_pose;
  k.scale_evidence = r.converged && !r.degenerate;
  kept_.push_back(std::move(k));
  if (config_.relax)
    graph_ = std::move(graph);
  else
    graph_.addNode(r.map_pose);
  if (!updates.empty()) {
    const auto apply_start = std::chrono::steady_clock::now();
    for (size_t u = 0; u < updates.size(); ++u) kept_[update_nodes[u]].pose = updates[u].second;
    if (dir_) {
      try {
        dir_->updatePoses(updates);
      } catch (const std::exception& e) {
        r.relax_problem = std::string("the corrected poses were not written: ") + e.what();
      }
    }
    rebuildMap();  // all scans at their corrected poses, this one included
    r.relax_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - apply_start).count();
  } else {
    const Eigen::Vector3f origin_map = T_map_base * sensor_origin.cast<float>();
    map_.add(in_map, &origin_map);
  }
  last_map_ = r.map_pose;
  last_odom_ = odom_pose;
  count_ = dir_ ? static_cast<size_t>(dir_->nextIndex()) : count_ + 1;
  r.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace slam
}  // namespace scanstop
