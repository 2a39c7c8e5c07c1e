/// relax_bench: the global relaxation (issue #17 point 4) next to its peer, PCL's Lu-Milios
/// implementation pcl::registration::LUM, on the same scans and the same graph, with ATE and time
/// of both against ground truth.
///
/// 1. Replays MAP_DIR with the shipped SLAM defaults and the relaxation's graph building on
///    (SlamConfig::relax, with its updates disabled, so every registration is the sequential one):
///    every edge the relaxation accepts (consecutive scans, loop candidates; each a pairwise
///    registration) is kept.
/// 2. Both solvers start from the same poses (the run's stored poses, i.e. the live SLAM; or
///    --start replay: the replay's) and solve that graph once:
///    - ours: PoseGraph::optimize (Ceres, 3 dof, the edges' information, robust loop edges);
///    - LUM: each scan voxel-filtered (--lum-voxel), every edge's correspondences found by nearest
///      neighbour (within --lum-corr) after aligning its two scans with the edge's pairwise result,
///      LUM::compute (6 dof, --lum-iterations) in --lum-rounds rounds (correspondences found
///      again at LUM's poses between rounds, as PCL's ELCH/LUM examples do).
/// 3. Prints the ATE (position RMS/max, yaw) of the start poses, of each solver's result and the
///    time of each (LUM: correspondence search included).
/// 4. Prints how wrong the graph's edges are against the true poses (chain and loop edges: the
///    residual in the first node's frame, its whitened size, the worst five) and the ATE of ours
///    solved from the true poses (the graph's own minimum, whatever the start).
///
/// Evaluation only (needs the true poses from mission_state.yaml); PCL's templates stay here.
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/lum.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/map_check.h"
#include "scanstop_common/options.h"
#include "scanstop_eval/truth_file.h"  // eval/: ground truth, not SLAM
#include "scanstop_slam/icp_slam.h"

using namespace scanstop;

namespace {

constexpr const char* kUsage =
    "usage: relax_bench MAP_DIR --truth mission_state.yaml [--start stored|replay] [--scans N]\n"
    "                   [--neighbours N] [--loop-candidates N] [--loop-min-gap N] [--max-distance M]\n"
    "                   [--loss cauchy|huber|none] [--loss-scale S]\n"
    "                   [--lum-voxel M] [--lum-corr M] [--lum-iterations N] [--lum-rounds N] [--skip-bad] [--verbose]\n"
    "  Replays MAP_DIR with the SLAM defaults to build the relaxation's pose graph, then solves it\n"
    "  from the same start poses with ours (Ceres, 3 dof) and PCL's LUM (6 dof) and prints the pose\n"
    "  error of every scan (ATE) and the time of each.\n"
    "  --start: the run's stored poses (default: what the live SLAM gave) or the replay's\n"
    "  --neighbours ... --loss-scale: the graph's SlamConfig relax_* / PoseGraphConfig settings\n"
    "  (defaults: the SLAM's; icp_slam.h)\n"
    "  --lum-voxel: LUM's cloud voxel filter [m] (default 0.1); --lum-corr: nearest-neighbour\n"
    "  correspondence distance [m] (default 0.1); --lum-iterations: per round (default 1);\n"
    "  --lum-rounds: correspondence rounds (default 5); --verbose: LUM's error after every round\n"
    "  (LUM with 10 iterations per round diverged on a 79-scan house map: 32 m RMS after 3 rounds)\n"
    "exit status: 0 done, 2 bad arguments, 1 unreadable or bad input\n";

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Eigen::Vector6f lumPose(const Pose2D& p) {
  Eigen::Vector6f v = Eigen::Vector6f::Zero();
  v(0) = static_cast<float>(p.x);
  v(1) = static_cast<float>(p.y);
  v(5) = static_cast<float>(p.yaw);
  return v;
}

/// Correspondences of an edge: points of `source` (base_link of node `to`) placed by T_target_source
/// into `target`'s frame, matched to their nearest target point within max_dist.
pcl::CorrespondencesPtr correspondences(const Cloud& source, const pcl::KdTreeFLANN<pcl::PointXYZ>& target_tree,
                                        const Eigen::Affine3f& T_target_source, double max_dist) {
  pcl::CorrespondencesPtr out(new pcl::Correspondences);
  std::vector<int> idx(1);
  std::vector<float> d2(1);
  const float max_d2 = static_cast<float>(max_dist * max_dist);
  for (size_t k = 0; k < source.size(); ++k) {
    const Eigen::Vector3f q = T_target_source * source[k].getVector3fMap();
    if (target_tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, idx, d2) == 1 && d2[0] <= max_d2)
      out->emplace_back(static_cast<int>(k), idx[0], d2[0]);
  }
  return out;
}

std::vector<Pose2D> lumPoses(const pcl::registration::LUM<pcl::PointXYZ>& lum, size_t n) {
  std::vector<Pose2D> out;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector6f p = lum.getPose(i);
    out.emplace_back(p(0), p(1), normalizeAngle(p(5)));
  }
  return out;
}

void printError(const char* what, const std::vector<Pose2D>& poses, const std::vector<std::optional<Pose2D>>& truth,
                double time_s) {
  const eval::TrajectoryError e = eval::trajectoryError(poses, truth);
  std::printf("  %-34s ATE RMS %6.2f cm  max %6.2f cm (scan %3zu)  yaw RMS %5.3f deg max %5.3f deg", what,
              e.rms_m * 100, e.max_m * 100, e.max_at, e.yaw_rms_deg, e.yaw_max_deg);
  if (time_s >= 0) std::printf("  %8.3f s", time_s);
  std::printf("\n");
}

/// How wrong the graph's edges are against the true poses, by kind (chain: the registration
/// against the map or odometry; loop: robust), and the worst few: a relaxation can only be as right
/// as its edges, and only trust them as far as their information matrices say.
void printEdgeErrors(const std::vector<slam::PoseGraphEdge>& edges, const std::vector<std::optional<Pose2D>>& truth) {
  struct Row {
    const slam::PoseGraphEdge* e;
    eval::MeasurementError m;
  };
  std::vector<Row> rows;
  for (const auto& e : edges)
    if (e.from < truth.size() && e.to < truth.size() && truth[e.from] && truth[e.to])
      rows.push_back({&e, eval::measurementError(*truth[e.from], *truth[e.to], e.T_from_to, e.information)});
  const auto pct = [](std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))];
  };
  for (const bool robust : {false, true}) {
    std::vector<double> t, y, w;
    double sum2 = 0.0;
    for (const Row& r : rows)
      if (r.e->robust == robust) {
        t.push_back(r.m.position_m * 100);
        y.push_back(r.m.yaw_deg);
        w.push_back(r.m.whitened);
        sum2 += r.m.position_m * r.m.position_m;
      }
    std::printf(
        "  edges at the true poses, %-5s %4zu: position RMS %5.2f cm p95 %5.2f max %6.2f cm; yaw p95 %5.3f deg;"
        " whitened median %6.1f p95 %7.1f\n",
        robust ? "loop" : "chain", t.size(), t.empty() ? 0.0 : 100 * std::sqrt(sum2 / t.size()), pct(t, 0.95),
        pct(t, 1.0), pct(y, 0.95), pct(w, 0.5), pct(w, 0.95));
  }
  std::sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.m.position_m > b.m.position_m; });
  for (size_t k = 0; k < std::min<size_t>(5, rows.size()); ++k)
    std::printf("    worst: %s %3zu -> %3zu off by (%6.2f, %6.2f) cm, %6.3f deg, whitened %7.1f\n",
                rows[k].e->robust ? "loop " : "chain", rows[k].e->from, rows[k].e->to, rows[k].m.residual.x() * 100,
                rows[k].m.residual.y() * 100, rows[k].m.residual.z() * 180 / M_PI, rows[k].m.whitened);
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_dir, truth_path, start = "stored";
  size_t max_scans = 0;
  double lum_voxel = 0.1, lum_corr = 0.1;
  int lum_iterations = 1, lum_rounds = 5;
  bool skip_bad = false, verbose = false;
  slam::SlamConfig relax;  // the relaxation settings of the graph (the SLAM defaults unless given)
  Options opts("relax_bench", kUsage);
  opts.positional("MAP_DIR", map_dir)
      .text("--truth", truth_path)
      .choice("--start", start, {"stored", "replay"})
      .integer("--scans", max_scans, size_t{0}, size_t{10000000})
      .real("--lum-voxel", lum_voxel, 0.01, 1.0)
      .real("--lum-corr", lum_corr, 0.001, 5.0)
      .integer("--lum-iterations", lum_iterations, 1, 1000)
      .integer("--lum-rounds", lum_rounds, 1, 100)
      .integer("--neighbours", relax.relax_neighbours, 0, 100)
      .integer("--loop-candidates", relax.relax_loop_candidates, 0, 100)
      .integer("--loop-min-gap", relax.relax_loop_min_gap, 2, 100000)
      .real("--max-distance", relax.relax_max_distance_m, 0.001, 1000.0)
      .real("--loss-scale", relax.graph.loss_scale, 1e-6, 1e6)
      .choice("--loss", relax.graph.loss, {"cauchy", "huber", "none"})
      .flag("--skip-bad", skip_bad)
      .flag("--verbose", verbose);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  if (truth_path.empty()) {
    std::cerr << "relax_bench: --truth mission_state.yaml is required (the ATE needs the true poses)\n";
    return kExitUsage;
  }
  try {
    const MapDirectory in = openMapForTool(
        map_dir, skip_bad, [](const std::string& w) { std::cerr << "relax_bench: warning: " << w << "\n"; });
    const std::vector<std::optional<Pose2D>> truth_by_index = eval::readTruth(truth_path);
    const size_t n = max_scans > 0 ? std::min(max_scans, in.size()) : in.size();
    if (n < 2) throw IoError(map_dir, "holds " + std::to_string(n) + " scan(s): a graph needs two");

    // 1. The graph: a replay with the relaxation's edges, its updates disabled.
    slam::SlamConfig config = relax;
    config.relax = true;
    config.relax_update_m = 10.0;
    config.relax_update_rad = M_PI;
    slam::IcpSlam replay(config);
    std::vector<Pose2D> replayed;
    std::vector<Cloud::Ptr> clouds;
    std::vector<std::optional<Pose2D>> truth;
    std::vector<Pose2D> stored;
    double replay_s = 0.0;
    pcl::VoxelGrid<pcl::PointXYZ> voxel;
    voxel.setLeafSize(static_cast<float>(lum_voxel), static_cast<float>(lum_voxel), static_cast<float>(lum_voxel));
    for (size_t i = 0; i < n; ++i) {
      const MapScanInfo& info = in.scans()[i];
      const PointCloud scan = in.loadScan(i);
      const slam::Registration r = replay.registerScan(scan, info.odom_pose, info.sensor_origin, info.stamp_s);
      replay_s += r.time_s;
      replayed.push_back(r.map_pose);
      stored.push_back(info.map_pose);
      truth.push_back(info.index < truth_by_index.size() ? truth_by_index[info.index] : std::nullopt);
      Cloud::Ptr raw(new Cloud), filtered(new Cloud);
      for (const auto& p : scan.points)
        if (p.allFinite()) raw->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
      voxel.setInputCloud(raw);
      voxel.filter(*filtered);
      clouds.push_back(filtered);
    }
    const std::vector<slam::PoseGraphEdge>& edges = replay.graph().edges();
    size_t loops = 0;
    for (const auto& e : edges) loops += e.robust ? 1 : 0;
    const std::vector<Pose2D>& start_poses = start == "stored" ? stored : replayed;
    std::printf("relax_bench: %s, %zu scans, %zu edges (%zu loop edges), replay %.1f s; start: %s poses\n",
                map_dir.c_str(), n, edges.size(), loops, replay_s, start.c_str());
    printError("start poses", start_poses, truth, -1);

    // 2a. Ours: the same graph, one solve from the start poses.
    slam::PoseGraph ours;
    for (const auto& p : start_poses) ours.addNode(p);
    for (const auto& e : edges) ours.addEdge(e);
    const slam::PoseGraphSummary s = ours.optimize(config.graph);
    if (!s.solved) std::printf("  ours: NOT solved: %s\n", s.message.c_str());
    printError("ours (PoseGraph, Ceres, 3 dof)", ours.poses(), truth, s.time_s);
    // The same graph solved from the true poses: where its minimum lies when the start is right
    // (away from the truth: the edges are biased, not the start or the solver).
    printEdgeErrors(edges, truth);
    slam::PoseGraph from_truth;
    for (size_t i = 0; i < n; ++i) from_truth.addNode(truth[i] ? *truth[i] : start_poses[i]);
    for (const auto& e : edges) from_truth.addEdge(e);
    const slam::PoseGraphSummary st = from_truth.optimize(config.graph);
    printError("ours from the true poses", from_truth.poses(), truth, st.time_s);

    // 2b. PCL's LUM on the same scans and edges.
    const auto lum_start = std::chrono::steady_clock::now();
    pcl::registration::LUM<pcl::PointXYZ> lum;
    std::vector<pcl::KdTreeFLANN<pcl::PointXYZ>> trees(n);
    for (size_t i = 0; i < n; ++i) {
      lum.addPointCloud(clouds[i], lumPose(start_poses[i]));
      trees[i].setInputCloud(clouds[i]);
    }
    lum.setMaxIterations(lum_iterations);
    lum.setConvergenceThreshold(0.0f);
    size_t corr_total = 0;
    for (int round = 0; round < lum_rounds; ++round) {
      corr_total = 0;
      for (const auto& e : edges) {
        // Round 0: the edge's pairwise result aligns the two; later rounds: LUM's current poses.
        const Eigen::Affine3f T =
            round == 0 ? Eigen::Affine3f(e.T_from_to.toIsometry3f().matrix())
                       : Eigen::Affine3f(lum.getTransformation(e.from).inverse() * lum.getTransformation(e.to));
        pcl::CorrespondencesPtr c = correspondences(*clouds[e.to], trees[e.from], T, lum_corr);
        corr_total += c->size();
        if (c->size() >= 3) lum.setCorrespondences(e.to, e.from, c);
      }
      lum.compute();
      if (round + 1 < lum_rounds && verbose) {
        char what[96];
        std::snprintf(what, sizeof what, "PCL LUM after round %d", round + 1);
        printError(what, lumPoses(lum, n), truth, -1);
      }
    }
    const double lum_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - lum_start).count();
    char what[96];
    std::snprintf(what, sizeof what, "PCL LUM (6 dof, %d x %d it)", lum_rounds, lum_iterations);
    printError(what, lumPoses(lum, n), truth, lum_s);
    std::printf("  (LUM: %zu correspondences over the edges in the last round, voxel %.2f m, distance %.2f m)\n",
                corr_total, lum_voxel, lum_corr);
  } catch (const std::exception& e) {
    std::cerr << "relax_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
