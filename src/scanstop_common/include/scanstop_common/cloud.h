#pragma once
/// Plain point-cloud and triangle-mesh containers used by every core library.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace scanstop {

/// A point cloud, optionally organized (height rows of width points, as a 3D scan: rows = planes,
/// columns = beams). Invalid points are NaN. Optional channels are empty or have one entry per point.
struct PointCloud {
  std::vector<Eigen::Vector3f> points;   ///< [m]
  std::vector<Eigen::Vector3f> normals;  ///< unit normals, or empty
  std::vector<float> ranges;             ///< measured range per point [m] (NaN where invalid), or empty
  uint32_t width = 0;                    ///< points per row (== size() when unorganized)
  uint32_t height = 1;                   ///< rows (1 when unorganized)

  size_t size() const { return points.size(); }
  bool empty() const { return points.empty(); }
  bool hasNormals() const { return !normals.empty(); }
  bool hasRanges() const { return !ranges.empty(); }
  bool isOrganized() const { return height > 1; }
  /// Makes the cloud an unorganized row of its current points.
  void setUnorganized() {
    width = static_cast<uint32_t>(points.size());
    height = 1;
  }
  /// Adds a point (and keeps width consistent for unorganized clouds).
  void push_back(const Eigen::Vector3f& p) {
    points.push_back(p);
    if (height <= 1) width = static_cast<uint32_t>(points.size());
  }
  /// Number of points with finite coordinates.
  size_t countFinite() const;
  /// Checks that the channels and the width x height layout agree; returns an empty string or the problem.
  std::string layoutProblem() const;
};

/// A copy with only the finite points (and their channels), unorganized.
PointCloud removeNonFinite(const PointCloud& cloud);

/// An indexed triangle mesh; faces are counter-clockwise seen from outside (normal = (b-a)x(c-a)).
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;  ///< [m]
  std::vector<Eigen::Vector3f> normals;   ///< per-vertex unit normals, or empty
  std::vector<Eigen::Vector3i> faces;     ///< vertex indices

  size_t numTriangles() const { return faces.size(); }
  /// Unit normal of face i (zero for a degenerate face).
  Eigen::Vector3f faceNormal(size_t i) const;
};

}  // namespace scanstop
