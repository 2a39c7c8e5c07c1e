#include "scanstop_slam/request_check.h"

#include <cmath>
#include <sstream>

namespace scanstop {
namespace slam {

std::string cloudLayoutProblem(const sensor_msgs::PointCloud2& msg, size_t max_points) {
  using PF = sensor_msgs::PointField;
  std::ostringstream out;
  const size_t n = static_cast<size_t>(msg.width) * msg.height;
  if (n == 0) {
    out << "the cloud is empty (width " << msg.width << " x height " << msg.height << ")";
    return out.str();
  }
  if (n > max_points) {
    out << "the cloud has " << n << " points (width " << msg.width << " x height " << msg.height << "), more than "
        << max_points;
    return out.str();
  }
  if (msg.is_bigendian) return "the cloud is big-endian (only little-endian is supported)";
  if (msg.point_step == 0) return "the cloud's point_step is 0";
  const PF* found[4] = {nullptr, nullptr, nullptr, nullptr};
  const char* names[4] = {"x", "y", "z", "range"};
  for (const PF& f : msg.fields)
    for (int k = 0; k < 4; ++k)
      if (f.name == names[k]) {
        if (found[k]) return std::string("the cloud has field '") + names[k] + "' twice";
        found[k] = &f;
      }
  for (int k = 0; k < 4; ++k) {
    const PF* f = found[k];
    if (!f) {
      if (k == 3) continue;  // range is optional
      return std::string("the cloud has no '") + names[k] + "' field (x, y and z float32 are required)";
    }
    if (f->datatype != PF::FLOAT32) {
      out << "the cloud's field '" << names[k] << "' has datatype " << static_cast<int>(f->datatype)
          << ", expected float32 (" << static_cast<int>(PF::FLOAT32) << ")";
      return out.str();
    }
    if (f->count != 1) {
      out << "the cloud's field '" << names[k] << "' has count " << f->count << ", expected 1";
      return out.str();
    }
    if (static_cast<size_t>(f->offset) + 4 > msg.point_step) {
      out << "the cloud's field '" << names[k] << "' at offset " << f->offset << " lies outside point_step "
          << msg.point_step;
      return out.str();
    }
    for (int j = 0; j < k; ++j)
      if (found[j] && std::abs(static_cast<long>(found[j]->offset) - static_cast<long>(f->offset)) < 4) {
        out << "the cloud's fields '" << names[j] << "' and '" << names[k] << "' overlap (offsets " << found[j]->offset
            << " and " << f->offset << ")";
        return out.str();
      }
  }
  const size_t min_row = static_cast<size_t>(msg.width) * msg.point_step;
  if (msg.row_step < min_row) {
    out << "the cloud's row_step " << msg.row_step << " is smaller than width " << msg.width << " x point_step "
        << msg.point_step << " = " << min_row;
    return out.str();
  }
  const size_t need = static_cast<size_t>(msg.row_step) * msg.height;
  if (msg.data.size() != need) {
    out << "the cloud's data has " << msg.data.size() << " bytes, its layout (row_step " << msg.row_step << " x height "
        << msg.height << ") needs " << need;
    return out.str();
  }
  return "";
}

std::string poseProblem(const geometry_msgs::Pose& pose, const std::string& what, double quaternion_tolerance) {
  std::ostringstream out;
  const auto& p = pose.position;
  const auto& q = pose.orientation;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    out << what << ".position (" << p.x << ", " << p.y << ", " << p.z << ") is not finite";
    return out.str();
  }
  if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) || !std::isfinite(q.w)) {
    out << what << ".orientation (" << q.x << ", " << q.y << ", " << q.z << ", " << q.w << ") is not finite";
    return out.str();
  }
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (std::abs(norm - 1.0) > quaternion_tolerance) {
    out << what << ".orientation (" << q.x << ", " << q.y << ", " << q.z << ", " << q.w << ") is not a unit quaternion"
        << " (norm " << norm << ")";
    return out.str();
  }
  return "";
}

std::string frameProblem(const std::string& frame_id, const std::string& expected, const std::string& what,
                         bool empty_ok) {
  if (frame_id == expected || (empty_ok && frame_id.empty())) return "";
  return what + " is in frame '" + frame_id + "', expected '" + expected + "'";
}

}  // namespace slam
}  // namespace scanstop
