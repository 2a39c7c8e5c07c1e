// explorer_bench: a full planning step on a 20 x 20 m map at 0.05 m (160,000 cells) with 20 scans,
// each stage's share, and OpenCV's exact distance transform on the same grid in the same run.
//   explorer_bench [--repeat N] [--write-map DIR]
// The world: four 10 x 10 m rooms joined by doors, with furniture; the 20 scans come from running
// the explorer itself on simulated scans (6 m range, line of sight). --write-map stores them as a
// map directory (for plan_step).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../test/scenes.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/options.h"
#include "scanstop_explorer/distance_transform.h"
#include "scanstop_explorer/explorer.h"

using namespace scanstop;
using namespace scanstop::explorer;

namespace {
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

test::Scene fourRooms() {
  test::Scene s = test::emptyScene(20.0, 20.0);
  s.geometry.origin_x = s.geometry.origin_y = -1.0;
  test::box(s, 0.0, 0.0, 20.0, 20.0, 1);
  test::box(s, 9.9, 0.0, 10.1, 20.0, 0);  // walls between the rooms
  test::box(s, 0.0, 9.9, 20.0, 10.1, 0);
  for (double c : {4.0, 15.0}) {  // doors
    test::box(s, 9.8, c, 10.2, c + 1.0, 1);
    test::box(s, c, 9.8, c + 1.0, 10.2, 1);
  }
  test::box(s, 2.0, 2.0, 3.5, 2.8, 0);  // furniture
  test::box(s, 14.0, 5.0, 14.6, 8.0, 0);
  test::box(s, 6.0, 14.0, 8.0, 15.0, 0);
  test::disc(s, 15.0, 15.0, 0.4, 0);
  test::box(s, 3.0, 16.0, 3.05, 16.05, 0);  // thin legs
  test::box(s, 4.2, 16.0, 4.25, 16.05, 0);
  return s;
}
}  // namespace

int main(int argc, char** argv) {
  int repeat = 20;
  std::string write_map;
  scanstop::Options opts("explorer_bench", "usage: explorer_bench [--repeat N (1-100000)] [--write-map DIR]\n");
  opts.integer("--repeat", repeat, 1, 100000).text("--write-map", write_map);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  const test::Scene world = fourRooms();
  const double range = 6.0;
  Explorer ex;
  std::vector<std::pair<Pose2D, std::vector<Eigen::Vector3f>>> scans;
  Eigen::Vector2d robot(5.0, 5.0);
  auto scanAt = [&](const Eigen::Vector2d& p) {
    const Pose2D pose(p.x(), p.y(), 0.0);
    scans.emplace_back(pose, test::simulateScan(world, p, range));
    ex.addScan(static_cast<uint32_t>(scans.size() - 1), pose, scans.back().second);
  };
  scanAt(robot);
  while (scans.size() < 20) {
    const PlanResult r = ex.plan(Pose2D(robot.x(), robot.y(), 0.0));
    if (!r.success || r.complete) {
      std::fprintf(stderr, "exploration stopped after %zu scans: %s %s\n", scans.size(), r.message.c_str(),
                   r.complete_reason.c_str());
      return 1;
    }
    for (size_t i = 1; i < r.path.size() && scans.size() < 20; ++i)
      if (r.scan_at[i]) scanAt(r.path[i]);
    robot = r.target;
  }
  if (!write_map.empty()) {
    MapDirectory md(write_map);
    for (size_t i = md.size(); i < scans.size(); ++i) {
      MapScanInfo info;
      info.index = static_cast<uint32_t>(i);
      info.map_pose = scans[i].first;
      info.odom_pose = scans[i].first;
      PointCloud cloud;
      const Eigen::Isometry3f T_base_map = scans[i].first.toIsometry3f().inverse();
      for (const auto& p : scans[i].second) cloud.push_back(T_base_map * p);
      md.append(info, cloud);
    }
    std::printf("wrote %zu scans to %s\n", scans.size(), write_map.c_str());
  }

  // The grid the planner sees: exactly the 20 x 20 m world (no extra margin).
  ExplorerConfig cfg;
  cfg.floor.grid_margin_m = 0.0;
  const Eigen::Vector2d lo(0.0, 0.0), hi(19.95, 19.95);
  PlanResult last;
  auto timeStep = [&](const char* title, const std::vector<std::pair<Pose2D, std::vector<Eigen::Vector3f>>>& set,
                      const Eigen::Vector2d& at) {
    std::map<std::string, std::vector<double>> stage;
    std::vector<std::string> order;
    std::vector<double> total;
    for (int k = 0; k < repeat; ++k) {
      Explorer e(cfg);  // fresh state each time (no blacklist effects), same scans
      e.reserveArea(lo, hi);
      for (size_t i = 0; i < set.size(); ++i) e.addScan(static_cast<uint32_t>(i), set[i].first, set[i].second);
      const auto t0 = std::chrono::steady_clock::now();
      last = e.plan(Pose2D(at.x(), at.y(), 0.0));
      total.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      for (const auto& [name, ms] : last.timings_ms) {
        if (!stage.count(name)) order.push_back(name);
        stage[name].push_back(ms);
      }
    }
    const GridGeometry& g = last.geometry;
    const double t_total = median(total);
    std::printf(
        "\n%s\ngrid %d x %d = %d cells (%.2f m), %zu scans; full planning step (median of %d): %.2f ms  "
        "[target < 100 ms]\n",
        title, g.width, g.height, g.width * g.height, g.resolution, set.size(), repeat, t_total);
    for (const std::string& name : order)
      std::printf("  %-28s %8.2f ms  %5.1f %%\n", name.c_str(), median(stage[name]),
                  100.0 * median(stage[name]) / t_total);
    std::printf(
        "  floor %.1f m^2, reachable %.1f m^2, landmarks %zu (coverage landmarks %d), graph edges %zu, open cells %zu, "
        "%s\n",
        last.floor_area_m2, last.reachable_area_m2, last.cost_map.nodes.size() - 1, last.cost_map.coverage_landmarks,
        last.cost_map.graph.edgeCount(), last.open_cells, last.complete ? "complete" : "not complete");
  };
  // (b) 20 scans spread over all four rooms (8 m range): nearly the whole map known.
  std::vector<std::pair<Pose2D, std::vector<Eigen::Vector3f>>> spread;
  for (double x : {2.5, 7.5, 12.5, 17.5})
    for (double y : {2.0, 6.0, 12.0, 16.0, 18.5}) {
      Eigen::Vector2d p(x, y);
      if (!world.free.at<uint8_t>(world.geometry.cellOf(p.x(), p.y()))) p.x() += 0.6;
      spread.emplace_back(Pose2D(p.x(), p.y(), 0.0), test::simulateScan(world, p, 8.0));
    }
  timeStep("(b) 20 scans spread over the four rooms, 8 m range", spread, {5.0, 5.0});
  timeStep("(a) 20 scans of the explorer's own first 20 steps, 6 m range", scans, robot);
  // (c) the same with the knowledge a scan really saw and the next scan by its expected gain (issue #19).
  cfg.planner.knowledge_model = "visibility";
  cfg.planner.target_score = "gain";
  cfg.planner.k_r_m = 2.5;
  timeStep("(c) as (a), knowledge_model visibility, target_score gain, k_r_m 2.5", scans, robot);
  std::printf("  target (%.2f, %.2f), expected gain %.1f m^2\n", last.target.x(), last.target.y(), last.target_gain_m2);

  // Distance transform: ours vs OpenCV's exact one, on the same floor mask.
  const cv::Mat mask = floorMask(last.states);
  std::vector<double> ours, theirs;
  cv::Mat d_ours, d_cv;
  for (int k = 0; k < std::max(repeat, 20); ++k) {
    auto t0 = std::chrono::steady_clock::now();
    d_ours = distanceTransform(mask);
    ours.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    t0 = std::chrono::steady_clock::now();
    cv::distanceTransform(mask, d_cv, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    theirs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::vector<double> sq_only;
  for (int k = 0; k < std::max(repeat, 20); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    const cv::Mat sq = squaredDistanceTransform(mask);
    sq_only.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  double max_diff = 0.0;
  cv::Mat diff;
  cv::absdiff(d_ours, d_cv, diff);
  cv::minMaxLoc(diff, nullptr, &max_diff);
  std::printf("\ndistance transform on the same %d x %d grid (median of %zu):\n", mask.cols, mask.rows, ours.size());
  std::printf("  ours (Meijster, float sqrt)   %8.3f ms\n", median(ours));
  std::printf("  ours squared (as planned)     %8.3f ms\n", median(sq_only));
  std::printf("  OpenCV DIST_MASK_PRECISE      %8.3f ms\n", median(theirs));
  std::printf("  ratio ours / OpenCV           %8.2f    [target <= 2]\n", median(ours) / median(theirs));
  std::printf("  max |ours - OpenCV|           %8.2g cells\n", max_diff);
  return 0;
}
