/// icp_replay: the thesis' offline IcpFileSlam on a saved map directory. Re-registers every scan of
/// MAP_DIR (its base_link cloud and the odometry pose stored with it) in order, as icp_slam_node
/// would have, with the parameters given here, and prints the corrected poses. With --truth (a
/// mission_state.yaml holding true_pose per scan, written by mission_node in simulation) it prints
/// the error of the replayed, the stored and the odometry-only pose against ground truth.
#include <sys/resource.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_slam/icp_slam.h"

using namespace scanstop;

namespace {

void usage() {
  std::cerr << "usage: icp_replay MAP_DIR [--out DIR] [--truth mission_state.yaml] [--mode 3dof|6dof]\n"
               "                  [--coarse-c-max M (0 = single stage)] [--refine-t-c M (0 = no refinement)]\n"
               "                  [--refine-r-c-deg D] [--refine-max-iterations N] [--refine-source-voxel M]\n"
               "                  [--refine-max-correction M] [--refine-max-correction-deg D] [--no-same-side]\n"
               "                  [--c-max M] [--t-c M] [--r-c-deg D] [--max-iterations N]\n"
               "                  [--source-voxel M] [--map-spacing M] [--max-points-per-voxel N] [--scans N] [--no-accelerate] [--quiet]\n"
               "                  [--relax] [--relax-neighbours N] [--relax-loop-candidates N] [--relax-loop-min-gap N]\n"
               "                  [--relax-max-distance M] [--relax-voxel M] [--relax-min-overlap F] [--relax-max-rms M]\n"
               "                  [--relax-update M] [--relax-update-deg D] [--relax-loss cauchy|huber|none] [--relax-loss-scale S]\n";
}

/// True poses by scan index (a scan the mission adopted after a crash may have none).
std::vector<std::optional<Pose2D>> readTruth(const std::string& path) {
  std::vector<std::optional<Pose2D>> out;
  const YAML::Node root = YAML::LoadFile(path);
  if (!root["scans"]) throw IoError(path, "has no 'scans' list (not a mission_state.yaml?)");
  for (const auto& s : root["scans"]) {
    const size_t index = s["index"].as<size_t>();
    if (index >= out.size()) out.resize(index + 1);
    const auto p = s["true_pose"];
    if (p && p.size() == 3) out[index] = Pose2D(p[0].as<double>(), p[1].as<double>(), p[2].as<double>());
  }
  return out;
}

double posErr(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double yawErrDeg(const Pose2D& a, const Pose2D& b) { return std::abs(normalizeAngle(a.yaw - b.yaw)) * 180.0 / M_PI; }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    usage();
    return 2;
  }
  std::string map_dir = argv[1], out_dir, truth_path;
  bool quiet = false;
  size_t max_scans = 0;
  slam::SlamConfig config;
  try {
    for (int i = 2; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw ConfigError(a + " needs a value");
        return argv[++i];
      };
      if (a == "--out") out_dir = next();
      else if (a == "--truth") truth_path = next();
      else if (a == "--mode") {
        const std::string m = next();
        if (m != "3dof" && m != "6dof") throw ConfigError("--mode must be 3dof or 6dof, not " + m);
        config.icp.six_dof = m == "6dof";
      } else if (a == "--c-max") config.icp.c_max_m = std::stod(next());
      else if (a == "--coarse-c-max") config.coarse_c_max_m = std::stod(next());
      else if (a == "--refine-t-c") config.refine_t_c_m = std::stod(next());
      else if (a == "--refine-r-c-deg") config.refine_r_c_rad = std::stod(next()) * M_PI / 180.0;
      else if (a == "--refine-max-iterations") config.refine_max_iterations = std::stoi(next());
      else if (a == "--refine-source-voxel") config.refine_source_voxel_m = std::stod(next());
      else if (a == "--refine-max-correction") config.refine_max_correction_m = std::stod(next());
      else if (a == "--refine-max-correction-deg") config.refine_max_correction_rad = std::stod(next()) * M_PI / 180.0;
      else if (a == "--no-same-side") config.icp.same_side = false;
      else if (a == "--t-c") config.icp.t_c_m = std::stod(next());
      else if (a == "--r-c-deg") config.icp.r_c_rad = std::stod(next()) * M_PI / 180.0;
      else if (a == "--max-iterations") config.icp.max_iterations = std::stoi(next());
      else if (a == "--max-points-per-voxel") config.max_points_per_voxel = std::stoi(next());
      else if (a == "--scans") max_scans = std::stoul(next());
      else if (a == "--source-voxel") config.source_voxel_m = std::stod(next());
      else if (a == "--map-spacing") config.map_spacing_m = std::stod(next());
      else if (a == "--quiet") quiet = true;
      else if (a == "--no-accelerate") config.icp.accelerate = false;
      else if (a == "--relax") config.relax = true;
      else if (a == "--relax-neighbours") config.relax_neighbours = std::stoi(next());
      else if (a == "--relax-loop-candidates") config.relax_loop_candidates = std::stoi(next());
      else if (a == "--relax-loop-min-gap") config.relax_loop_min_gap = std::stoi(next());
      else if (a == "--relax-max-distance") config.relax_max_distance_m = std::stod(next());
      else if (a == "--relax-voxel") config.relax_voxel_m = std::stod(next());
      else if (a == "--relax-min-overlap") config.relax_min_overlap = std::stod(next());
      else if (a == "--relax-max-rms") config.relax_max_rms_m = std::stod(next());
      else if (a == "--relax-update") config.relax_update_m = std::stod(next());
      else if (a == "--relax-update-deg") config.relax_update_rad = std::stod(next()) * M_PI / 180.0;
      else if (a == "--relax-loss") config.graph.loss = next();
      else if (a == "--relax-loss-scale") config.graph.loss_scale = std::stod(next());
      else throw ConfigError("unknown option " + a);
    }
    config.validate();
    const MapDirectory in(map_dir);
    if (in.size() == 0) throw IoError(map_dir, "holds no scans (poses.csv missing or empty)");
    std::vector<std::optional<Pose2D>> truth;
    if (!truth_path.empty()) truth = readTruth(truth_path);
    slam::IcpSlam slam(config, out_dir);
    if (slam.scanCount() != 0) throw IoError(out_dir, "already holds scans; give an empty or new --out directory");
    std::vector<Pose2D> poses;
    double total_s = 0.0, err_sum = 0.0, relax_s = 0.0, relax_max_s = 0.0;
    size_t relaxations = 0, relax_edges = 0, relax_tried = 0;
    size_t err_n = 0, last_truth = 0;
    const size_t n = max_scans > 0 ? std::min(max_scans, in.size()) : in.size();
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
        if (i < truth.size() && truth[i])
          std::printf("  err %5.1f cm %5.2f deg (stored %5.1f cm, odometry %6.1f cm)", posErr(r.map_pose, *truth[i]) * 100,
                      yawErrDeg(r.map_pose, *truth[i]), posErr(info.map_pose, *truth[i]) * 100,
                      posErr(info.odom_pose, *truth[i]) * 100);
        std::printf("\n");
        if (!r.converged) std::printf("          %s\n", r.failure.c_str());
        if (config.relax)
          std::printf("          relax: %d/%d pairwise edges, %s%s, %zu poses moved, at most %.1f cm %.2f deg, %.2f s%s%s\n",
                      r.relax_edges, r.relax_edges_tried, r.relax_solved ? "solved" : "NOT solved",
                      r.relaxed ? ", applied" : "", r.relax_moved, r.relax_max_moved_m * 100,
                      r.relax_max_moved_rad * 180 / M_PI, r.relax_time_s, r.relax_problem.empty() ? "" : ": ",
                      r.relax_problem.c_str());
        if (r.refine_rejected)
          std::printf("          refinement moved %.1f cm, %.2f deg: rejected, the thesis stage's result stands\n",
                      r.refine_moved_m * 100, r.refine_moved_rad * 180.0 / M_PI);
      }
      if (i < truth.size() && truth[i]) {
        err_sum += posErr(r.map_pose, *truth[i]);
        ++err_n;
        last_truth = i;
      }
    }
    std::printf("%zu scans, %.2f s registration in all (%.2f s per scan)", n, total_s, total_s / n);
    if (err_n > 0) {
      const size_t last = last_truth;
      std::printf("; mean error %.1f cm; error of scan %zu %.1f cm %.2f deg (odometry alone %.1f cm)", err_sum / err_n * 100,
                  last, posErr(poses[last], *truth[last]) * 100, yawErrDeg(poses[last], *truth[last]),
                  posErr(in.scans()[last].odom_pose, *truth[last]) * 100);
    }
    std::printf("\n");
    if (config.relax)
      std::printf("relaxation: %zu of %zu scans applied it, %zu of %zu pairwise edges accepted, %.2f s per scan (max %.2f s)\n",
                  relaxations, n, relax_edges, relax_tried, relax_s / n, relax_max_s);
    if (err_n > 0) {
      // Errors over all scans with ground truth: the final poses (after the last relaxation) and the
      // poses as each scan was registered.
      const std::vector<slam::ScanPose> final_poses = slam.poses();
      const auto report = [&](const char* what, const std::function<Pose2D(size_t)>& pose) {
        double sum2 = 0.0, max = 0.0, sum2_yaw = 0.0, max_yaw = 0.0;
        size_t m = 0;
        for (size_t i = 0; i < n; ++i) {
          if (i >= truth.size() || !truth[i]) continue;
          const double e = posErr(pose(i), *truth[i]), y = yawErrDeg(pose(i), *truth[i]);
          sum2 += e * e;
          sum2_yaw += y * y;
          max = std::max(max, e);
          max_yaw = std::max(max_yaw, y);
          ++m;
        }
        std::printf("%-28s over %zu scans: position RMS %6.1f cm max %6.1f cm; yaw RMS %5.2f deg max %5.2f deg\n", what, m,
                    std::sqrt(sum2 / m) * 100, max * 100, std::sqrt(sum2_yaw / m), max_yaw);
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
