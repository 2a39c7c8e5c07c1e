#include "scanstop_mesher/mesh_markers.h"

#include <algorithm>
#include <cmath>

#include "scanstop_common/config.h"

namespace scanstop {
namespace mesher {
namespace {

std_msgs::ColorRGBA heightColor(float t) {
  // Blue -> cyan -> green -> yellow -> red.
  t = std::min(1.0f, std::max(0.0f, t));
  std_msgs::ColorRGBA c;
  c.a = 1.0f;
  c.r = std::min(1.0f, std::max(0.0f, 4.0f * t - 2.0f));
  c.g = t < 0.25f ? 4.0f * t : (t > 0.75f ? 4.0f - 4.0f * t : 1.0f);
  c.b = std::min(1.0f, std::max(0.0f, 2.0f - 4.0f * t));
  return c;
}

}  // namespace

MeshColoring parseColoring(const std::string& value, const std::string& parameter) {
  requireOneOf(parameter, value, {"height", "normal"});
  return value == "height" ? MeshColoring::kHeight : MeshColoring::kNormal;
}

visualization_msgs::MarkerArray meshToMarkers(const TriangleMesh& mesh, const std::string& frame_id,
                                              const ros::Time& stamp, MeshColoring coloring, size_t max_triangles,
                                              size_t max_total, float max_z) {
  visualization_msgs::MarkerArray out;
  visualization_msgs::Marker clear;
  clear.header.frame_id = frame_id;
  clear.header.stamp = stamp;
  clear.ns = "mesh";
  clear.action = visualization_msgs::Marker::DELETEALL;
  out.markers.push_back(clear);
  max_triangles = std::max<size_t>(1, max_triangles);
  std::vector<size_t> below;  // faces with every vertex at or below max_z
  below.reserve(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    if (mesh.vertices[t[0]].z() <= max_z && mesh.vertices[t[1]].z() <= max_z && mesh.vertices[t[2]].z() <= max_z)
      below.push_back(f);
  }
  if (below.empty()) return out;

  float z_lo = 0.0f, z_hi = 1.0f;
  if (coloring == MeshColoring::kHeight) {
    std::vector<float> z;
    z.reserve(mesh.vertices.size());
    for (const auto& v : mesh.vertices)
      if (v.z() <= max_z) z.push_back(v.z());
    const size_t lo = z.size() / 50, hi = z.size() - 1 - z.size() / 50;
    std::nth_element(z.begin(), z.begin() + lo, z.end());
    z_lo = z[lo];
    std::nth_element(z.begin(), z.begin() + hi, z.end());
    z_hi = z[hi];
    if (!(z_hi > z_lo)) z_hi = z_lo + 1.0f;
  }
  std::vector<std_msgs::ColorRGBA> colors(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (coloring == MeshColoring::kHeight) {
      colors[i] = heightColor((mesh.vertices[i].z() - z_lo) / (z_hi - z_lo));
    } else {
      Eigen::Vector3f n = i < mesh.normals.size() ? mesh.normals[i] : Eigen::Vector3f::UnitZ();
      if (!n.allFinite()) n = Eigen::Vector3f::UnitZ();
      colors[i].r = std::abs(n.x());
      colors[i].g = std::abs(n.y());
      colors[i].b = std::abs(n.z());
      colors[i].a = 1.0f;
    }
  }
  if (coloring == MeshColoring::kNormal && mesh.normals.size() != mesh.vertices.size()) {
    // A soup (STL) has no vertex normals: colour each corner by its face normal.
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const Eigen::Vector3f n = mesh.faceNormal(f);
      for (int k = 0; k < 3; ++k) {
        colors[mesh.faces[f][k]].r = std::abs(n.x());
        colors[mesh.faces[f][k]].g = std::abs(n.y());
        colors[mesh.faces[f][k]].b = std::abs(n.z());
      }
    }
  }
  const size_t stride = max_total > 0 ? (below.size() + max_total - 1) / max_total : 1;
  std::vector<size_t> shown;
  shown.reserve(below.size() / stride + 1);
  for (size_t i = 0; i < below.size(); i += stride) shown.push_back(below[i]);
  for (size_t first = 0, id = 0; first < shown.size(); first += max_triangles, ++id) {
    const size_t last = std::min(shown.size(), first + max_triangles);
    visualization_msgs::Marker m;
    m.header.frame_id = frame_id;
    m.header.stamp = stamp;
    m.ns = "mesh";
    m.id = static_cast<int>(id);
    m.type = visualization_msgs::Marker::TRIANGLE_LIST;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.scale.x = m.scale.y = m.scale.z = 1.0;
    m.color.r = m.color.g = m.color.b = m.color.a = 1.0f;
    m.points.reserve(3 * (last - first));
    m.colors.reserve(3 * (last - first));
    for (size_t s = first; s < last; ++s)
      for (int k = 0; k < 3; ++k) {
        const int vi = mesh.faces[shown[s]][k];
        const Eigen::Vector3f& v = mesh.vertices[vi];
        geometry_msgs::Point p;
        p.x = v.x();
        p.y = v.y();
        p.z = v.z();
        m.points.push_back(p);
        m.colors.push_back(colors[vi]);
      }
    out.markers.push_back(std::move(m));
  }
  return out;
}

}  // namespace mesher
}  // namespace scanstop
