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
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_slam/icp.h"

using namespace scanstop;

namespace {

void usage() {
  std::cerr << "usage: icp_register TARGET SOURCE [--init x,y,z,yaw] [--mode 3dof|6dof] [--c-max M]\n"
               "                    [--t-c M] [--r-c-deg D] [--max-iterations N] [--voxel M] [--no-accelerate] [--json]\n"
               "                    [--method point_to_point|point_to_plane] [--degeneracy-ratio R] [--no-remap]\n"
               "                    [--map-voxel M]\n"
               "  TARGET, SOURCE: .pcd, .ply or .xyz point clouds (metres)\n"
               "  --init: initial guess of SOURCE in TARGET's frame (yaw in degrees; default 0,0,0,0)\n"
               "  --voxel: keep one source point per voxel of this size before matching (default 0 = all)\n"
               "  --method: default point_to_point (thesis Algorithm 4)\n"
               "  --map-voxel: voxel size of TARGET's voxel map, i.e. the scale of its normals (default: c_max)\n"
               "  --degeneracy-ratio: weak direction below this eigenvalue ratio (default 0.01);\n"
               "  --no-remap: move along weak directions too (default: keep the initial guess there)\n";
}

Eigen::Isometry3d parseInit(const std::string& s) {
  double v[4];
  if (std::sscanf(s.c_str(), "%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3]) != 4)
    throw ConfigError("--init must be x,y,z,yaw_deg (four comma-separated numbers), not '" + s + "'");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(v[3] * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    usage();
    return 2;
  }
  const std::string target_path = argv[1], source_path = argv[2];
  slam::IcpConfig config;
  Eigen::Isometry3d init = Eigen::Isometry3d::Identity();
  double voxel = 0.0;
  double map_voxel = 0.0;  // 0: c_max
  bool json = false;
  try {
    for (int i = 3; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw ConfigError(a + " needs a value");
        return argv[++i];
      };
      if (a == "--init") init = parseInit(next());
      else if (a == "--mode") {
        const std::string m = next();
        if (m != "3dof" && m != "6dof") throw ConfigError("--mode must be 3dof or 6dof, not " + m);
        config.six_dof = m == "6dof";
      } else if (a == "--c-max") config.c_max_m = std::stod(next());
      else if (a == "--t-c") config.t_c_m = std::stod(next());
      else if (a == "--r-c-deg") config.r_c_rad = std::stod(next()) * M_PI / 180.0;
      else if (a == "--max-iterations") config.max_iterations = std::stoi(next());
      else if (a == "--voxel") voxel = std::stod(next());
      else if (a == "--json") json = true;
      else if (a == "--no-accelerate") config.accelerate = false;
      else if (a == "--method") config.method = slam::parseIcpMethod(next(), "--method");
      else if (a == "--degeneracy-ratio") config.degeneracy_ratio = std::stod(next());
      else if (a == "--no-remap") config.degeneracy_remap = false;
      else if (a == "--map-voxel") map_voxel = std::stod(next());
      else throw ConfigError("unknown option " + a);
    }
    config.validate();
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
    std::string weak, weak_json;  // the weak direction, space- and comma-separated
    for (Eigen::Index k = 0; k < r.weak_direction.size(); ++k) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.6f", r.weak_direction(k));
      weak += (k ? " " : "") + std::string(buf);
      weak_json += (k ? ", " : "") + std::string(buf);
    }
    // JSON has no inf / NaN: null.
    char condition_json[32] = "null";
    if (std::isfinite(r.condition)) std::snprintf(condition_json, sizeof condition_json, "%.6g", r.condition);
    if (json) {
      std::printf(
          "{\"translation\": [%.9f, %.9f, %.9f], \"quaternion\": [%.9f, %.9f, %.9f, %.9f], \"yaw\": %.9f, "
          "\"iterations\": %d, \"correspondences\": %zu, \"rms\": %.9f, \"overlap\": %.6f, \"converged\": %s, "
          "\"failure\": \"%s\", \"time_s\": %.6f, \"method\": \"%s\", \"condition\": %s, \"weak_direction\": [%s], "
          "\"degenerate\": %s, \"remapped\": %s, \"information_pairs\": %zu}\n",
          t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), yaw, r.iterations, r.correspondences, r.rms_m, r.overlap,
          r.converged ? "true" : "false", r.failure.c_str(), time_s, slam::toString(config.method).c_str(),
          condition_json, weak_json.c_str(), r.degenerate ? "true" : "false", r.remapped ? "true" : "false",
          r.information_pairs);
    } else {
      std::printf("translation  %.6f %.6f %.6f m\nquaternion   %.6f %.6f %.6f %.6f (x y z w)\nyaw          %.4f deg\n",
                  t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), yaw * 180.0 / M_PI);
      std::printf("iterations   %d\ncorrespondences %zu (overlap %.3f)\nrms          %.6f m\nconverged    %s%s%s\ntime         %.3f s\n",
                  r.iterations, r.correspondences, r.overlap, r.rms_m, r.converged ? "yes" : "no",
                  r.converged ? "" : ": ", r.failure.c_str(), time_s);
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
