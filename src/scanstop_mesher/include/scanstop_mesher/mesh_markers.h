#pragma once
/// Conversion of a triangle mesh to rviz markers (TRIANGLE_LIST, split into several markers when
/// large) with per-vertex colours by height or by normal.

#include <visualization_msgs/MarkerArray.h>

#include <limits>
#include <string>

#include "scanstop_common/cloud.h"

namespace scanstop {
namespace mesher {

enum class MeshColoring { kHeight, kNormal };

/// Parses "height" or "normal"; throws ConfigError naming the parameter otherwise.
MeshColoring parseColoring(const std::string& value, const std::string& parameter);

/// The mesh as TRIANGLE_LIST markers of at most max_triangles each (namespace "mesh", ids 0..),
/// preceded by a DELETEALL marker that clears an earlier, larger mesh. Height colours run from
/// blue (2nd percentile of the vertex heights) to red (98th percentile); normal colours are
/// |n| as RGB. Frame frame_id, points in metres. A mesh of more than max_total triangles is shown
/// by every k-th triangle (k = ceil(faces / max_total); 0 = no limit) to keep the messages small.
/// Triangles with a vertex above max_z [m] are left out (the ceiling, which hides a room seen from
/// above; +inf = none), before the stride and the colour scale are taken.
visualization_msgs::MarkerArray meshToMarkers(const TriangleMesh& mesh, const std::string& frame_id,
                                              const ros::Time& stamp, MeshColoring coloring, size_t max_triangles,
                                              size_t max_total = 0,
                                              float max_z = std::numeric_limits<float>::infinity());

}  // namespace mesher
}  // namespace scanstop
