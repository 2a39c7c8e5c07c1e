/// slam_bench: ICP SLAM speed on full simulated scans. Registers the scans of LIST (lines
/// "FILE x y yaw": a scan in base_link and its true pose in the world, metres and radians) one after
/// the other with IcpSlam, each against all scans before it, starting from odometry that drifts
/// (every leg 3 % too long and 0.5 deg of yaw added), and prints per scan the registration time,
/// iterations, map size and the pose error against the truth next to the odometry's error.
/// The last line is the time of the last scan against the map of all the others.
///
/// usage: slam_bench LIST [--mode 3dof|6dof] [--c-max M] [--coarse-c-max M] [--refine-t-c M (0 = no refinement)]
///                  [--method point_to_point|point_to_plane] [--degeneracy-ratio R] [--degeneracy-remap 0|1]
/// (cond: the final stage's condition number, * when degenerate.)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/options.h"
#include "scanstop_slam/icp_slam.h"

using namespace scanstop;

namespace {

struct Entry {
  std::string file;
  Pose2D truth;
};

std::vector<Entry> readList(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot be opened");
  std::vector<Entry> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Entry e;
    if (!(s >> e.file >> e.truth.x >> e.truth.y >> e.truth.yaw))
      throw IoError(path, "line " + std::to_string(n) + ": expected 'FILE x y yaw', got '" + line + "'");
    out.push_back(e);
  }
  if (out.size() < 2) throw IoError(path, "lists fewer than two scans");
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  slam::SlamConfig config;
  std::string list_path, mode = "3dof", remap = config.icp.degeneracy_remap ? "1" : "0";
  Options opts(
      "slam_bench",
      "usage: slam_bench LIST [--mode 3dof|6dof] [--c-max M] [--coarse-c-max M] [--refine-t-c M]\n"
      "                  [--method point_to_point|point_to_plane] [--degeneracy-ratio R] [--degeneracy-remap 0|1]\n"
      "  LIST: lines 'FILE x y yaw' (scan in base_link, true pose in the world [m, rad])\n");
  opts.positional("LIST", list_path)
      .choice("--mode", mode, {"3dof", "6dof"})
      .real("--c-max", config.icp.c_max_m, 0.001, 5.0)
      .real("--coarse-c-max", config.coarse_c_max_m, 0.001, 5.0)
      .real("--refine-t-c", config.refine_t_c_m, 1e-9, 1.0)
      .custom("--method", [&](const std::string& v) { config.icp.method = slam::parseIcpMethod(v, "--method"); })
      .real("--degeneracy-ratio", config.icp.degeneracy_ratio, 0.0, 1.0)
      .choice("--degeneracy-remap", remap, {"0", "1"});
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  config.icp.six_dof = mode == "6dof";
  config.icp.degeneracy_remap = remap == "1";
  try {
    config.validate();
    const std::vector<Entry> list = readList(list_path);
    std::vector<PointCloud> scans;
    size_t total_points = 0;
    for (const auto& e : list) {
      scans.push_back(readCloud(e.file));
      total_points += scans.back().countFinite();
    }
    std::printf("%zu scans, %.0f finite points per scan on average, mode %s, %s, remap %s\n", scans.size(),
                static_cast<double>(total_points) / scans.size(), config.icp.six_dof ? "6dof" : "3dof",
                slam::toString(config.icp.method).c_str(), config.icp.degeneracy_remap ? "on" : "off");
    std::printf("%5s %9s %8s %5s %10s %10s %12s %12s %9s\n", "scan", "time_s", "iters", "ok", "map_pts", "err_cm",
                "err_deg", "odom_err_cm", "cond");
    // Ground truth and odometry relative to the first scan's pose (the map frame).
    const Pose2D origin = list[0].truth;
    slam::IcpSlam slam(config);
    Pose2D odom;
    double sum_time = 0.0, last_time = 0.0;
    for (size_t i = 0; i < scans.size(); ++i) {
      const Pose2D truth = origin.inverse() * list[i].truth;
      if (i > 0) {
        const Pose2D step = (origin.inverse() * list[i - 1].truth).between(truth);
        odom = odom * Pose2D(step.x * 1.03, step.y * 1.03, step.yaw + 0.5 * M_PI / 180);
      }
      const size_t map_before = slam.map().size();
      const auto start = std::chrono::steady_clock::now();
      const slam::Registration r = slam.registerScan(scans[i], odom, Eigen::Vector3d(0, 0, 0.45), i * 40.0);
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (i > 0) sum_time += t;
      last_time = t;
      std::printf("%5zu %9.3f %8d %5s %10zu %10.2f %12.3f %12.2f %8.3g%s\n", i, t, r.iterations,
                  r.converged ? "yes" : "NO", map_before,
                  std::hypot(r.map_pose.x - truth.x, r.map_pose.y - truth.y) * 100,
                  std::abs(normalizeAngle(r.map_pose.yaw - truth.yaw)) * 180 / M_PI,
                  std::hypot(odom.x - truth.x, odom.y - truth.y) * 100, r.condition, r.degenerate ? "*" : "");
    }
    std::printf(
        "registration (scans 1..%zu): mean %.3f s; the last scan against the map of the %zu before it: %.3f s\n",
        scans.size() - 1, sum_time / (scans.size() - 1), scans.size() - 1, last_time);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "slam_bench: " << e.what() << "\n";
    return 1;
  }
}
