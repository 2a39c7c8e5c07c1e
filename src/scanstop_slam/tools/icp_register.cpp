/// icp_register: registers SOURCE to TARGET (PCD/PLY/XYZ) with the ICP of thesis Algorithm 4 and
/// prints the transform of SOURCE into TARGET's frame, iterations, residual, converged flag, the
/// information matrix's condition and weak direction (IcpResult) and time; --json prints the same
/// as one JSON object. --method point_to_plane: point-to-plane ICP on the map's voxel normals.
/// No ROS needed.
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/options.h"
#include "scanstop_slam/icp.h"

using namespace scanstop;

namespace {

constexpr const char* kUsage =
    "usage: icp_register TARGET SOURCE [--init x,y,z,yaw] [--mode 3dof|6dof] [--c-max M]\n"
    "                    [--t-c M] [--r-c-deg D] [--max-iterations N] [--voxel M] [--no-accelerate] [--json]\n"
    "                    [--method point_to_point|point_to_plane] [--degeneracy-ratio R] [--no-remap]\n"
    "                    [--map-voxel M]\n"
    "  TARGET, SOURCE: .pcd, .ply or .xyz point clouds (metres)\n"
    "  --init: initial guess of SOURCE in TARGET's frame (yaw in degrees; default 0,0,0,0; each within +-10000)\n"
    "  --c-max [0.001, 5] m, --t-c [1e-9, 1] m, --r-c-deg [1e-7, 57.29] deg, --max-iterations [1, 10000]\n"
    "  --voxel: keep one source point per voxel of this size before matching, [0, 10] m (default 0 = all)\n"
    "  --method: default point_to_point (thesis Algorithm 4)\n"
    "  --map-voxel: voxel size of TARGET's voxel map, i.e. the scale of its normals, [0, 10] m (default 0: c_max)\n"
    "  --degeneracy-ratio: weak direction below this eigenvalue ratio, [0, 1] (default 0.01);\n"
    "  --no-remap: move along weak directions too (default: keep the initial guess there)\n"
    "exit status: 0 converged, 3 not converged, 2 bad arguments, 1 unreadable input\n";

Eigen::Isometry3d initFrom(const std::vector<double>& v) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(v[3] * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

}  // namespace

int main(int argc, char** argv) {
  std::string target_path, source_path, mode = "3dof";
  slam::IcpConfig config;
  Eigen::Isometry3d init = Eigen::Isometry3d::Identity();
  double voxel = 0.0;
  double map_voxel = 0.0;  // 0: c_max
  bool json = false;
  Options opts("icp_register", kUsage);
  opts.positional("TARGET", target_path)
      .positional("SOURCE", source_path)
      .custom(
          "--init",
          [&](const std::string& v) { init = initFrom(parseRealListArg("--init", v, 4, -1e4, 1e4, "x,y,z,yaw_deg")); })
      .choice("--mode", mode, {"3dof", "6dof"})
      .real("--c-max", config.c_max_m, 0.001, 5.0)
      .real("--t-c", config.t_c_m, 1e-9, 1.0)
      .real("--r-c-deg", config.r_c_rad, 1e-7, 57.29, M_PI / 180.0)
      .integer("--max-iterations", config.max_iterations, 1, 10000)
      .real("--voxel", voxel, 0.0, 10.0)
      .flag("--json", json)
      .flag("--no-accelerate", config.accelerate, false)
      .custom("--method", [&](const std::string& v) { config.method = slam::parseIcpMethod(v, "--method"); })
      .real("--degeneracy-ratio", config.degeneracy_ratio, 0.0, 1.0)
      .flag("--no-remap", config.degeneracy_remap, false)
      .real("--map-voxel", map_voxel, 0.0, 10.0);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  config.six_dof = mode == "6dof";
  try {
    try {
      config.validate();
    } catch (const ConfigError& e) {
      std::cerr << "icp_register: " << e.what() << "\n";
      return kExitUsage;
    }
    const PointCloud target = readCloud(target_path);
    const PointCloud source = readCloud(source_path);
    const auto start = std::chrono::steady_clock::now();
    slam::VoxelMap map(map_voxel > 0.0 ? map_voxel : config.c_max_m, 1000000);
    map.add(target.points);
    if (map.size() == 0) throw IoError(target_path, "has no finite points");
    const auto src = slam::voxelDownsample(source.points, voxel);
    if (src.empty()) throw IoError(source_path, "has no finite points");
    const slam::IcpResult r = slam::icp(map, src, init, config);
    const double time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Eigen::Vector3d t = r.T_target_source.translation();
    const Eigen::Quaterniond q(r.T_target_source.linear());
    const Eigen::Matrix3d R = r.T_target_source.linear();
    const double yaw = std::atan2(R(1, 0), R(0, 0));
    std::string weak;  // the weak direction, space-separated
    for (Eigen::Index k = 0; k < r.weak_direction.size(); ++k) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.6f", r.weak_direction(k));
      weak += (k ? " " : "") + std::string(buf);
    }
    // JSON has no inf / NaN: null (jsonNumber); the failure text is escaped (jsonString).
    if (json) {
      const auto n = [](double v, int precision = 12) { return jsonNumber(v, precision); };
      std::ostringstream weak_json;
      for (Eigen::Index k = 0; k < r.weak_direction.size(); ++k)
        weak_json << (k ? ", " : "") << n(r.weak_direction(k), 6);
      std::printf(
          "{\"translation\": [%s, %s, %s], \"quaternion\": [%s, %s, %s, %s], \"yaw\": %s, "
          "\"iterations\": %d, \"correspondences\": %zu, \"rms\": %s, \"overlap\": %s, \"converged\": %s, "
          "\"failure\": %s, \"time_s\": %s, \"method\": \"%s\", \"condition\": %s, \"weak_direction\": [%s], "
          "\"degenerate\": %s, \"remapped\": %s, \"information_pairs\": %zu}\n",
          n(t.x()).c_str(), n(t.y()).c_str(), n(t.z()).c_str(), n(q.x()).c_str(), n(q.y()).c_str(), n(q.z()).c_str(),
          n(q.w()).c_str(), n(yaw).c_str(), r.iterations, r.correspondences, n(r.rms_m).c_str(),
          n(r.overlap, 6).c_str(), r.converged ? "true" : "false", jsonString(r.failure).c_str(), n(time_s, 6).c_str(),
          slam::toString(config.method).c_str(), n(r.condition, 6).c_str(), weak_json.str().c_str(),
          r.degenerate ? "true" : "false", r.remapped ? "true" : "false", r.information_pairs);
    } else {
      std::printf("translation  %.6f %.6f %.6f m\nquaternion   %.6f %.6f %.6f %.6f (x y z w)\nyaw          %.4f deg\n",
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), yaw * 180.0 / M_PI);
      std::printf(
          "iterations   %d\ncorrespondences %zu (overlap %.3f)\nrms          %.6f m\nconverged    %s%s%s\ntime         "
          "%.3f s\n",
          r.iterations, r.correspondences, r.overlap, r.rms_m, r.converged ? "yes" : "no", r.converged ? "" : ": ",
          r.failure.c_str(), time_s);
      std::printf("method       %s\ncondition    %.4g (%zu planar pairs)%s%s\nweak direction %s (%s)\n",
                  slam::toString(config.method).c_str(), r.condition, r.information_pairs,
                  r.degenerate ? ", degenerate" : "", r.remapped ? ", remapped" : "", weak.c_str(),
                  config.six_dof ? "x y z rx ry rz" : "x y yaw");
    }
    return r.converged ? 0 : 3;
  } catch (const std::exception& e) {
    std::cerr << "icp_register: " << e.what() << "\n";
    return 1;
  }
}
