/// pcl_icp_bench: PCL's IterativeClosestPoint (point-to-point, kd-tree correspondences) on one pair,
/// with the parameters of icp_register, for bench/slam_bench.sh. Prints one JSON object like
/// icp_register --json. PCL's templates stay in this one translation unit.
///
/// usage: pcl_icp_bench TARGET SOURCE --init x,y,z,yaw_deg [--c-max M] [--max-iterations N]
///                      [--t-c M] [--r-c-deg D]
/// The convergence test is ICP's own with t_c and r_c (PCL: transformation epsilon t_c^2,
/// rotation epsilon cos(r_c)); PCL also stops on its default relative-fitness test.
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"

using namespace scanstop;

namespace {

/// Exposes PCL's iteration count (protected member).
class CountingIcp : public pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> {
 public:
  int iterations() const { return nr_iterations_; }
};

pcl::PointCloud<pcl::PointXYZ>::Ptr toPcl(const PointCloud& cloud, const std::string& path) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr out(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : cloud.points)
    if (p.allFinite()) out->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  if (out->empty()) throw IoError(path, "has no finite points");
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: pcl_icp_bench TARGET SOURCE --init x,y,z,yaw_deg [--c-max M] [--max-iterations N] "
                 "[--t-c M] [--r-c-deg D]\n";
    return 2;
  }
  try {
    double init[4] = {0, 0, 0, 0}, c_max = 0.1, t_c = 0.0005, r_c_deg = 0.02;
    int max_iterations = 100;
    for (int i = 3; i < argc; ++i) {
      const std::string a = argv[i];
      if (i + 1 >= argc) throw ConfigError(a + " needs a value");
      const std::string v = argv[++i];
      if (a == "--init") {
        if (std::sscanf(v.c_str(), "%lf,%lf,%lf,%lf", &init[0], &init[1], &init[2], &init[3]) != 4)
          throw ConfigError("--init must be x,y,z,yaw_deg (four comma-separated numbers), not '" + v + "'");
      } else if (a == "--c-max")
        c_max = std::stod(v);
      else if (a == "--max-iterations")
        max_iterations = std::stoi(v);
      else if (a == "--t-c")
        t_c = std::stod(v);
      else if (a == "--r-c-deg")
        r_c_deg = std::stod(v);
      else
        throw ConfigError("unknown option " + a);
    }
    if (!(c_max > 0.0) || max_iterations < 1 || !(t_c > 0.0) || !(r_c_deg > 0.0))
      throw ConfigError("--c-max, --t-c, --r-c-deg must be > 0 and --max-iterations >= 1");
    const auto target = toPcl(readCloud(argv[1]), argv[1]);
    const auto source = toPcl(readCloud(argv[2]), argv[2]);
    Eigen::Matrix4f guess = Eigen::Matrix4f::Identity();
    guess.topLeftCorner<3, 3>() =
        Eigen::AngleAxisf(static_cast<float>(init[3] * M_PI / 180.0), Eigen::Vector3f::UnitZ()).toRotationMatrix();
    guess.topRightCorner<3, 1>() = Eigen::Vector3f(init[0], init[1], init[2]);

    const auto start = std::chrono::steady_clock::now();
    CountingIcp icp;
    icp.setInputTarget(target);  // the kd-tree of the target is built here (counted in the time)
    icp.setInputSource(source);
    icp.setMaxCorrespondenceDistance(c_max);
    icp.setMaximumIterations(max_iterations);
    icp.setTransformationEpsilon(t_c * t_c);
    icp.setTransformationRotationEpsilon(std::cos(r_c_deg * M_PI / 180.0));
    pcl::PointCloud<pcl::PointXYZ> aligned;
    icp.align(aligned, guess);
    const double time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    const Eigen::Matrix4d T = icp.getFinalTransformation().cast<double>();
    const Eigen::Quaterniond q(Eigen::Matrix3d(T.topLeftCorner<3, 3>()));
    // Mean squared distance of the pairs within c_max (PCL compares its argument with squared distances).
    const double fitness_mse = icp.getFitnessScore(c_max * c_max);
    std::printf(
        "{\"translation\": [%.9f, %.9f, %.9f], \"quaternion\": [%.9f, %.9f, %.9f, %.9f], \"yaw\": %.9f, "
        "\"iterations\": %d, \"rms\": %.9f, \"converged\": %s, \"time_s\": %.6f}\n",
        T(0, 3), T(1, 3), T(2, 3), q.x(), q.y(), q.z(), q.w(), std::atan2(T(1, 0), T(0, 0)), icp.iterations(),
        std::sqrt(fitness_mse), icp.hasConverged() ? "true" : "false", time_s);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "pcl_icp_bench: " << e.what() << "\n";
    return 1;
  }
}
