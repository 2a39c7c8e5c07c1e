#include "scanstop_eval/truth_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <stdexcept>

#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace eval {

std::vector<std::optional<Pose2D>> readTruth(const std::string& path) {
  std::vector<std::optional<Pose2D>> out;
  YAML::Node root;
  const std::string problem = inputFileProblem(path);  // a directory: libstdc++'s "basic_filebuf::underflow"
  if (!problem.empty()) throw IoError(path, problem);
  try {
    root = YAML::Load(readFile(path));
  } catch (const YAML::Exception& e) {
    throw IoError(path, std::string("not valid YAML: ") + e.what());
  }
  if (!root.IsMap() || !root["scans"] || !root["scans"].IsSequence())
    throw IoError(path, "has no 'scans' list (not a mission_state.yaml?)");
  size_t k = 0;
  for (const auto& s : root["scans"]) {
    const std::string where = "scans[" + std::to_string(k++) + "]";
    try {
      const double index_value = s["index"].as<double>();
      if (!(index_value >= 0 && index_value <= 9999999 && index_value == std::floor(index_value)))
        throw IoError(path, where + ": index " + s["index"].as<std::string>() + " is not an integer from 0 to 9999999");
      const size_t index = static_cast<size_t>(index_value);
      if (index >= out.size()) out.resize(index + 1);
      const auto p = s["true_pose"];
      if (p && p.size() == 3) {
        const Pose2D pose(p[0].as<double>(), p[1].as<double>(), p[2].as<double>());
        if (!pose.isFinite() || std::abs(pose.x) > 1e4 || std::abs(pose.y) > 1e4)
          throw IoError(path, where + " (scan " + std::to_string(index) + "): true_pose " + pose.toString() +
                                  " is not finite or beyond the 10000 m pose limit");
        out[index] = pose;
      }
    } catch (const YAML::Exception& e) {
      throw IoError(path, where + ": " + e.what());
    }
  }
  return out;
}

TrajectoryError trajectoryError(const std::vector<Pose2D>& poses, const std::vector<std::optional<Pose2D>>& truth) {
  if (poses.size() != truth.size())
    throw std::invalid_argument("trajectoryError: " + std::to_string(poses.size()) + " poses but " +
                                std::to_string(truth.size()) + " true poses");
  TrajectoryError e;
  double sum2 = 0.0, sum2_yaw = 0.0;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (!truth[i]) continue;
    const double d = std::hypot(poses[i].x - truth[i]->x, poses[i].y - truth[i]->y);
    const double y = std::abs(normalizeAngle(poses[i].yaw - truth[i]->yaw)) * 180.0 / M_PI;
    sum2 += d * d;
    sum2_yaw += y * y;
    if (d > e.max_m) e.max_at = i;
    e.max_m = std::max(e.max_m, d);
    e.yaw_max_deg = std::max(e.yaw_max_deg, y);
    ++e.scans;
  }
  if (e.scans > 0) {
    e.rms_m = std::sqrt(sum2 / e.scans);
    e.yaw_rms_deg = std::sqrt(sum2_yaw / e.scans);
  }
  return e;
}

MeasurementError measurementError(const Pose2D& true_from, const Pose2D& true_to, const Pose2D& measured,
                                  const Eigen::Matrix3d& information) {
  const double c = std::cos(true_from.yaw), s = std::sin(true_from.yaw);
  const double dx = true_to.x - true_from.x, dy = true_to.y - true_from.y;
  MeasurementError m;
  m.residual = Eigen::Vector3d(c * dx + s * dy - measured.x, -s * dx + c * dy - measured.y,
                               normalizeAngle(true_to.yaw - true_from.yaw - measured.yaw));
  m.position_m = std::hypot(m.residual.x(), m.residual.y());
  m.yaw_deg = std::abs(m.residual.z()) * 180.0 / M_PI;
  m.whitened = std::sqrt(std::max(0.0, m.residual.dot(information * m.residual)));
  return m;
}

}  // namespace eval
}  // namespace scanstop
