/// icp_replay: the thesis' offline IcpFileSlam on a saved map directory. Re-registers every scan of
/// MAP_DIR (its base_link cloud and the odometry pose stored with it) in order, as icp_slam_node
/// would have, with the parameters given here, and prints the corrected poses. With --truth (a
/// mission_state.yaml holding true_pose per scan, written by mission_node in simulation) it prints
/// the error of the replayed, the stored and the odometry-only pose against ground truth.
#include <sys/resource.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/options.h"
#include "scanstop_eval/truth_file.h"  // eval/: ground truth, not SLAM
#include "scanstop_slam/icp_slam.h"

using namespace scanstop;

namespace {

constexpr const char* kUsage =
    "usage: icp_replay MAP_DIR [--out DIR] [--truth mission_state.yaml] [--mode 3dof|6dof] [--skip-bad]\n"
    "                  [--method point_to_point|point_to_plane] [--source-centroids | --no-source-centroids]\n"
    "                  [--degeneracy-ratio R] [--no-remap] [--no-odom-scale] [--no-odom-turn]\n"
    "                  [--odom-scale-min-travel M] [--odom-scale-later-end]\n"
    "                  [--coarse-point-to-plane] [--isolated odometry|truth [--from N]]\n"
    "                  [--odometry-prior | --no-odometry-prior] [--prior-sigma M] [--prior-sigma-per-m F] "
    "[--prior-sigma-deg D]\n"
    "                  [--prior-sigma-angle-per-rad F] [--prior-sigma-deg-per-m D] [--information-points N]\n"
    "                  [--information-sigma M] [--prior-gate SIGMAS] [--prior-all-directions]\n"
    "                  [--odometry-gate SIGMAS (default 5, 0 = off)] [--odometry-gate-rms-ratio F]\n"
    "                  [--odometry-gate-weak-rms-ratio F]\n"
    "                  [--failure-retry-degeneracy-ratio R (default 0.05, 0 = off)]\n"
    "                  [--coarse-c-max M (0 = single stage)] [--refine-t-c M (0 = no refinement)]\n"
    "                  [--refine-r-c-deg D] [--refine-max-iterations N] [--refine-source-voxel M]\n"
    "                  [--refine-max-correction M] [--refine-max-correction-deg D] [--no-same-side]\n"
    "                  [--c-max M] [--t-c M] [--r-c-deg D] [--max-iterations N]\n"
    "                  [--source-voxel M] [--map-spacing M] [--max-points-per-voxel N] [--scans N] [--no-accelerate] "
    "[--quiet]\n"
    "                  [--relax] [--relax-neighbours N] [--relax-loop-candidates N] [--relax-loop-min-gap N]\n"
    "                  [--relax-max-distance M] [--relax-voxel M] [--relax-min-overlap F] [--relax-max-rms M]\n"
    "                  [--relax-update M] [--relax-update-deg D] [--relax-loss cauchy|huber|none] [--relax-loss-scale "
    "S]\n"
    "  --isolated: (with --truth) register every scan alone against the earlier scans at their true\n"
    "              poses, from the true pose of the scan before composed with the odometry leg\n"
    "              (odometry) or from its own true pose (truth), and print each registration's error:\n"
    "              the error of one registration, without the drift before it; --from N: only scans\n"
    "              N on are registered (the earlier ones only enter the map)\n"
    "  --skip-bad: replay the good scans of a map with bad lines or scan files (each named on stderr);\n"
    "              default: refuse such a map, naming the first problem\n"
    "  numbers are checked against the ranges of the SLAM configuration (an error names option, value and range)\n"
    "exit status: 0 replayed, 2 bad arguments, 1 unreadable or bad input\n";

double posErr(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double yawErrDeg(const Pose2D& a, const Pose2D& b) { return std::abs(normalizeAngle(a.yaw - b.yaw)) * 180.0 / M_PI; }

/// A degenerate registration's weak direction, in the map frame (the registration reports it in
/// the scan's frame at its result; unit length in x, y [m], yaw [rad]) and the errors of the guess
/// and the result along it, or "" for a well-constrained registration.
std::string weakText(const slam::Registration& r, const Pose2D& truth) {
  if (!r.degenerate || r.weak_direction.size() < 3) return "";
  const double c = std::cos(r.map_pose.yaw), s = std::sin(r.map_pose.yaw);
  const double wx = r.weak_direction(0), wy = r.weak_direction(1);
  const double mx = c * wx - s * wy, my = s * wx + c * wy, norm = std::hypot(mx, my);
  auto along = [&](const Pose2D& p) { return norm > 0 ? ((p.x - truth.x) * mx + (p.y - truth.y) * my) / norm : 0.0; };
  char buf[160];
  std::snprintf(buf, sizeof buf, " along (%.2f, %.2f, %.2f) in the map; error along it: guess %.1f cm, result %.1f cm",
                mx, my, r.weak_direction(r.weak_direction.size() - 1), along(r.guess) * 100, along(r.map_pose) * 100);
  return buf;
}

/// --isolated: every scan registered alone against the earlier scans at their true poses.
int replayIsolated(const MapDirectory& in, const std::vector<std::optional<Pose2D>>& truth,
                   const slam::SlamConfig& config, bool from_truth, size_t max_scans, size_t from, bool quiet) {
  const slam::IcpSlam slam(config);
  slam::VoxelMap map(config.icp.c_max_m, config.max_points_per_voxel, config.map_spacing_m);
  const size_t n = max_scans > 0 ? std::min(max_scans, in.size()) : in.size();
  double sum2 = 0.0, max = 0.0, sum2_yaw = 0.0, max_yaw = 0.0, total_s = 0.0;
  size_t m = 0, failed = 0, max_at = 0;
  std::optional<size_t> prev;  // position of the last scan with a true pose
  for (size_t i = 0; i < n; ++i) {
    const MapScanInfo& info = in.scans()[i];
    const std::optional<Pose2D> t = info.index < truth.size() ? truth[info.index] : std::nullopt;
    if (!t) continue;
    const PointCloud scan = in.loadScan(i);
    if (prev && i >= from) {
      const MapScanInfo& before = in.scans()[*prev];
      const Pose2D guess = from_truth ? *t : *truth[before.index] * before.odom_pose.between(info.odom_pose);
      const slam::Registration r =
          slam.registerAgainst(map, scan, guess, info.sensor_origin, before.odom_pose.between(info.odom_pose));
      total_s += r.time_s;
      const double e = posErr(r.map_pose, *t), y = yawErrDeg(r.map_pose, *t);
      if (!quiet)
        std::printf(
            "scan %3zu: %s err %5.1f cm (dx %5.1f dy %5.1f) %5.2f deg, guess off %5.1f cm, it %3d, overlap %.2f, "
            "condition %.2f, prior %.1f sigma%s%s%s%s%s\n",
            i, r.converged ? "ok    " : "FAILED", e * 100, (r.map_pose.x - t->x) * 100, (r.map_pose.y - t->y) * 100, y,
            posErr(guess, *t) * 100, r.iterations, r.overlap, r.condition, r.prior_distance,
            r.prior_rejected ? " (beyond prior_gate: registered without its weight)" : "",
            r.degenerate ? " degenerate" : "", weakText(r, *t).c_str(),
            !r.gate_retried   ? ""
            : r.gate_widened  ? " (beyond odometry_gate: registered again with failure_retry_degeneracy_ratio)"
            : r.gate_replaced ? " (beyond odometry_gate: registered again without the coarse stage)"
                              : " (beyond odometry_gate; the second registration did not stand)",
            !r.failure_retried   ? ""
            : r.failure_replaced ? " (failed, registered again with failure_retry_degeneracy_ratio)"
                                 : " (failed, and again with failure_retry_degeneracy_ratio)");
      failed += r.converged ? 0 : 1;
      sum2 += e * e;
      sum2_yaw += y * y;
      if (e > max) max_at = i;
      max = std::max(max, e);
      max_yaw = std::max(max_yaw, y);
      ++m;
    }
    const Eigen::Isometry3f T = t->toIsometry3f();
    std::vector<Eigen::Vector3f> in_map;
    in_map.reserve(scan.points.size());
    for (const auto& p : scan.points)
      if (p.allFinite()) in_map.push_back(T * p);
    const Eigen::Vector3f origin = T * info.sensor_origin.cast<float>();
    map.add(in_map, &origin);
    prev = i;
  }
  if (m == 0) {
    std::printf("isolated: no registration (fewer than two scans with a true pose)\n");
    return 0;
  }
  std::printf(
      "isolated registrations from %s over %zu scans: position RMS %6.2f cm max %6.2f cm (scan %zu); yaw RMS %5.3f deg "
      "max %5.3f deg; %zu failed; %.2f s per scan\n",
      from_truth ? "the true pose" : "the odometry leg", m, std::sqrt(sum2 / m) * 100, max * 100, max_at,
      std::sqrt(sum2_yaw / m), max_yaw, failed, total_s / m);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_dir, out_dir, truth_path, isolated, mode = "3dof",
                                                      method = slam::toString(slam::SlamConfig().icp.method);
  bool quiet = false, skip_bad = false;
  size_t max_scans = 0, isolated_from = 0;
  slam::SlamConfig config;
  const double deg = M_PI / 180.0;
  Options opts("icp_replay", kUsage);
  opts.positional("MAP_DIR", map_dir)
      .text("--out", out_dir)
      .text("--truth", truth_path)
      .choice("--isolated", isolated, {"odometry", "truth"})
      .choice("--mode", mode, {"3dof", "6dof"})
      .choice("--method", method, {"point_to_point", "point_to_plane"})
      .flag("--source-centroids", config.source_centroids)
      .flag("--no-source-centroids", config.source_centroids, false)
      .real("--degeneracy-ratio", config.icp.degeneracy_ratio, 0.0, 1.0)
      .flag("--no-remap", config.icp.degeneracy_remap, false)
      .flag("--odometry-prior", config.odometry_prior)
      .flag("--no-odometry-prior", config.odometry_prior, false)
      .real("--prior-sigma", config.prior_sigma_m, 1e-6, 10.0)
      .real("--prior-sigma-per-m", config.prior_sigma_per_m, 0.0, 1.0)
      .real("--prior-sigma-deg", config.prior_sigma_rad, 1e-4, 180.0, deg)
      .real("--prior-sigma-angle-per-rad", config.prior_sigma_rad_per_rad, 0.0, 1.0)
      .real("--prior-sigma-deg-per-m", config.prior_sigma_rad_per_m, 0.0, 57.0, deg)
      .real("--prior-gate", config.prior_gate, 1e-6, 1e6)
      .real("--odometry-gate", config.odometry_gate, 0.0, 1e6)
      .real("--odometry-gate-rms-ratio", config.odometry_gate_rms_ratio, 1.0, 100.0)
      .real("--odometry-gate-weak-rms-ratio", config.odometry_gate_weak_rms_ratio, 1.0, 100.0)
      .real("--failure-retry-degeneracy-ratio", config.failure_retry_degeneracy_ratio, 0.0, 1.0)
      .flag("--prior-all-directions", config.icp.prior_all_directions)
      .real("--information-points", config.icp.information_points, 1e-6, 1e6)
      .real("--information-sigma", config.icp.information_sigma_m, 1e-6, 1.0)
      .flag("--no-odom-scale", config.odom_scale_estimation, false)
      .flag("--no-odom-turn", config.odom_turn_estimation, false)
      .flag("--coarse-point-to-plane", config.coarse_point_to_point, false)
      .real("--odom-scale-min-travel", config.odom_scale_min_travel_m, 0.01, 100.0)
      .flag("--odom-scale-later-end", config.odom_scale_both_ends, false)
      .flag("--skip-bad", skip_bad)
      .real("--c-max", config.icp.c_max_m, 0.001, 5.0)
      .real("--coarse-c-max", config.coarse_c_max_m, 0.0, 5.0)
      .real("--refine-t-c", config.refine_t_c_m, 0.0, 0.01)
      .real("--refine-r-c-deg", config.refine_r_c_rad, 1e-7, 0.01 / deg, deg)
      .integer("--refine-max-iterations", config.refine_max_iterations, 1, 10000)
      .real("--refine-source-voxel", config.refine_source_voxel_m, 0.0, 1.0)
      .real("--refine-max-correction", config.refine_max_correction_m, 0.0, 10.0)
      .real("--refine-max-correction-deg", config.refine_max_correction_rad, 0.0, 180.0, deg)
      .flag("--no-same-side", config.icp.same_side, false)
      .real("--t-c", config.icp.t_c_m, 1e-9, 1.0)
      .real("--r-c-deg", config.icp.r_c_rad, 1e-7, 57.29, deg)
      .integer("--max-iterations", config.icp.max_iterations, 1, 10000)
      .integer("--max-points-per-voxel", config.max_points_per_voxel, 1, 100000)
      .integer("--scans", max_scans, size_t{0}, size_t{10000000})
      .integer("--from", isolated_from, size_t{0}, size_t{10000000})
      .real("--source-voxel", config.source_voxel_m, 0.0, 1.0)
      .real("--map-spacing", config.map_spacing_m, 0.0, 5.0)
      .flag("--quiet", quiet)
      .flag("--no-accelerate", config.icp.accelerate, false)
      .flag("--relax", config.relax)
      .integer("--relax-neighbours", config.relax_neighbours, 0, 100)
      .integer("--relax-loop-candidates", config.relax_loop_candidates, 0, 100)
      .integer("--relax-loop-min-gap", config.relax_loop_min_gap, 2, 100000)
      .real("--relax-max-distance", config.relax_max_distance_m, 1e-6, 1000.0)
      .real("--relax-voxel", config.relax_voxel_m, 0.01, 1.0)
      .real("--relax-min-overlap", config.relax_min_overlap, 0.0, 1.0)
      .real("--relax-max-rms", config.relax_max_rms_m, 1e-6, 1.0)
      .real("--relax-update", config.relax_update_m, 0.0, 10.0)
      .real("--relax-update-deg", config.relax_update_rad, 0.0, 180.0, deg)
      .choice("--relax-loss", config.graph.loss, {"cauchy", "huber", "none"})
      .real("--relax-loss-scale", config.graph.loss_scale, 1e-6, 1e6);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  config.icp.six_dof = mode == "6dof";
  config.icp.method = slam::parseIcpMethod(method, "--method");
  try {
    try {
      config.validate();
    } catch (const ConfigError& e) {
      std::cerr << "icp_replay: " << e.what() << "\n";
      return kExitUsage;
    }
    const MapDirectory in = openMapForTool(
        map_dir, skip_bad, [](const std::string& w) { std::cerr << "icp_replay: warning: " << w << "\n"; });
    std::vector<std::optional<Pose2D>> truth;
    if (!truth_path.empty()) truth = eval::readTruth(truth_path);
    if (isolated_from > 0 && isolated.empty()) {
      std::cerr << "icp_replay: --from needs --isolated (a full replay registers every scan)\n";
      return kExitUsage;
    }
    if (!isolated.empty()) {
      if (truth.empty()) {
        std::cerr << "icp_replay: --isolated needs --truth (the true poses to build the map from)\n";
        return kExitUsage;
      }
      return replayIsolated(in, truth, config, isolated == "truth", max_scans, isolated_from, quiet);
    }
    slam::IcpSlam slam(config, out_dir);
    if (slam.scanCount() != 0) throw IoError(out_dir, "already holds scans; give an empty or new --out directory");
    std::vector<Pose2D> poses;
    double total_s = 0.0, err_sum = 0.0, relax_s = 0.0, relax_max_s = 0.0;
    size_t relaxations = 0, relax_edges = 0, relax_tried = 0;
    size_t err_n = 0, last_truth = 0;
    const size_t n = max_scans > 0 ? std::min(max_scans, in.size()) : in.size();
    // The true pose of the scan at position i of the map (by its index: a skipped scan leaves a gap).
    const auto truthOf = [&](size_t i) -> const std::optional<Pose2D>& {
      static const std::optional<Pose2D> none;
      const size_t index = in.scans()[i].index;
      return index < truth.size() ? truth[index] : none;
    };
    for (size_t i = 0; i < n; ++i) {
      const MapScanInfo& info = in.scans()[i];
      const slam::Registration r = slam.registerScan(in.loadScan(i), info.odom_pose, info.sensor_origin, info.stamp_s);
      total_s += r.time_s;
      relax_s += r.relax_time_s;
      relax_max_s = std::max(relax_max_s, r.relax_time_s);
      relaxations += r.relaxed ? 1 : 0;
      relax_edges += static_cast<size_t>(r.relax_edges);
      relax_tried += static_cast<size_t>(r.relax_edges_tried);
      poses.push_back(r.map_pose);
      if (!quiet) {
        std::printf("scan %3zu: (%7.3f %7.3f %7.2f deg) %s it %3d rms %5.1f mm %5.2f s", i, r.map_pose.x, r.map_pose.y,
                    r.map_pose.yaw * 180.0 / M_PI, r.converged ? "ok    " : "FAILED", r.iterations, r.rms_m * 1000.0,
                    r.time_s);
        if (truthOf(i))
          std::printf("  err %5.1f cm %5.2f deg (stored %5.1f cm, odometry %6.1f cm)",
                      posErr(r.map_pose, *truthOf(i)) * 100, yawErrDeg(r.map_pose, *truthOf(i)),
                      posErr(info.map_pose, *truthOf(i)) * 100, posErr(info.odom_pose, *truthOf(i)) * 100);
        std::printf("\n");
        if (!r.converged) std::printf("          %s\n", r.failure.c_str());
        if (r.failure_retried)
          std::printf("          failed (%s), registered again with degeneracy_ratio %.3f: %s\n",
                      r.first_failure.c_str(), config.failure_retry_degeneracy_ratio,
                      r.failure_replaced ? "that result stands" : "failed too");
        if (config.relax)
          std::printf(
              "          relax: %d/%d pairwise edges, %s%s, %zu poses moved, at most %.1f cm %.2f deg, %.2f s%s%s\n",
              r.relax_edges, r.relax_edges_tried, r.relax_solved ? "solved" : "NOT solved",
              r.relaxed ? ", applied" : "", r.relax_moved, r.relax_max_moved_m * 100,
              r.relax_max_moved_rad * 180 / M_PI, r.relax_time_s, r.relax_problem.empty() ? "" : ": ",
              r.relax_problem.c_str());
        if (r.refine_rejected)
          std::printf("          refinement moved %.1f cm, %.2f deg: rejected, the thesis stage's result stands\n",
                      r.refine_moved_m * 100, r.refine_moved_rad * 180.0 / M_PI);
      }
      if (truthOf(i)) {
        err_sum += posErr(r.map_pose, *truthOf(i));
        ++err_n;
        last_truth = i;
      }
    }
    std::printf("%zu scans, %.2f s registration in all (%.2f s per scan)", n, total_s, total_s / n);
    if (err_n > 0) {
      const size_t last = last_truth;
      std::printf("; mean error %.1f cm; error of scan %zu %.1f cm %.2f deg (odometry alone %.1f cm)",
                  err_sum / err_n * 100, last, posErr(poses[last], *truthOf(last)) * 100,
                  yawErrDeg(poses[last], *truthOf(last)), posErr(in.scans()[last].odom_pose, *truthOf(last)) * 100);
    }
    std::printf("\n");
    if (config.relax)
      std::printf(
          "relaxation: %zu of %zu scans applied it, %zu of %zu pairwise edges accepted, %.2f s per scan (max %.2f s)\n",
          relaxations, n, relax_edges, relax_tried, relax_s / n, relax_max_s);
    if (err_n > 0) {
      // Errors over all scans with ground truth: the final poses (after the last relaxation) and the
      // poses as each scan was registered.
      const std::vector<slam::ScanPose> final_poses = slam.poses();
      const auto report = [&](const char* what, const std::function<Pose2D(size_t)>& pose) {
        std::vector<Pose2D> at;
        std::vector<std::optional<Pose2D>> true_at;
        for (size_t i = 0; i < n; ++i) {
          at.push_back(pose(i));
          true_at.push_back(truthOf(i));
        }
        const eval::TrajectoryError e = eval::trajectoryError(at, true_at);
        std::printf("%-28s over %zu scans: position RMS %6.1f cm max %6.1f cm; yaw RMS %5.2f deg max %5.2f deg\n", what,
                    e.scans, e.rms_m * 100, e.max_m * 100, e.yaw_rms_deg, e.yaw_max_deg);
      };
      report("error, final poses", [&](size_t i) { return final_poses.at(i).map_pose; });
      report("error, as registered", [&](size_t i) { return poses[i]; });
      report("error, stored in MAP_DIR", [&](size_t i) { return in.scans()[i].map_pose; });
      report("error, odometry", [&](size_t i) { return in.scans()[i].odom_pose; });
    }
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    std::printf("peak memory (max RSS) %.0f MB\n", usage.ru_maxrss / 1024.0);
  } catch (const std::exception& e) {
    std::cerr << "icp_replay: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
