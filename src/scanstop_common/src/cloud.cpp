#include "scanstop_common/cloud.h"

#include <Eigen/Geometry>
#include <string>

namespace scanstop {

size_t PointCloud::countFinite() const {
  size_t n = 0;
  for (const auto& p : points) n += p.allFinite() ? 1 : 0;
  return n;
}

std::string PointCloud::layoutProblem() const {
  if (static_cast<size_t>(width) * height != points.size())
    return "width x height = " + std::to_string(width) + " x " + std::to_string(height) + " but the cloud has " +
           std::to_string(points.size()) + " points";
  if (!normals.empty() && normals.size() != points.size())
    return std::to_string(normals.size()) + " normals for " + std::to_string(points.size()) + " points";
  if (!ranges.empty() && ranges.size() != points.size())
    return std::to_string(ranges.size()) + " ranges for " + std::to_string(points.size()) + " points";
  return {};
}

PointCloud removeNonFinite(const PointCloud& cloud) {
  PointCloud out;
  out.points.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.points[i].allFinite()) continue;
    out.points.push_back(cloud.points[i]);
    if (cloud.hasNormals()) out.normals.push_back(cloud.normals[i]);
    if (cloud.hasRanges()) out.ranges.push_back(cloud.ranges[i]);
  }
  out.setUnorganized();
  return out;
}

Eigen::Vector3f TriangleMesh::faceNormal(size_t i) const {
  const Eigen::Vector3i& f = faces[i];
  Eigen::Vector3f n = (vertices[f[1]] - vertices[f[0]]).cross(vertices[f[2]] - vertices[f[0]]);
  const float len = n.norm();
  return len > 0.0f ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

}  // namespace scanstop
