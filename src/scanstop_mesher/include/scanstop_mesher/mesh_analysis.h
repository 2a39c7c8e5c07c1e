#pragma once
/// Topology and accuracy checks of triangle meshes (for the CLI, the tests and the benchmark).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "scanstop_common/cloud.h"

namespace scanstop {
namespace mesher {

/// Counts describing a mesh's topology. Vertices without a face are not counted.
struct MeshTopology {
  size_t vertices = 0;  ///< vertices used by at least one face
  size_t edges = 0;     ///< undirected edges
  size_t faces = 0;
  size_t degenerate_faces = 0;      ///< faces with a repeated vertex index
  size_t boundary_edges = 0;        ///< edges with one face
  size_t nonmanifold_edges = 0;     ///< edges with more than two faces
  size_t inconsistent_edges = 0;    ///< edges with two faces that run the edge in the same direction
  size_t nonmanifold_vertices = 0;  ///< vertices whose faces form more than one fan (edge-connected group)
  size_t components = 0;            ///< edge-connected groups of faces
  size_t boundary_loops = 0;        ///< closed chains of boundary edges (when the mesh is manifold)
  long euler() const { return static_cast<long>(vertices) - static_cast<long>(edges) + static_cast<long>(faces); }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0 && inconsistent_edges == 0; }
};

MeshTopology analyzeTopology(const TriangleMesh& mesh);

/// Makes every vertex of an edge-manifold face list manifold: at a vertex whose faces form more
/// than one fan, the faces of all but the largest fan are removed (repeated until no such vertex
/// is left). Returns the number of faces removed.
size_t dropPinchedFans(std::vector<Eigen::Vector3i>& faces, size_t num_vertices);
/// The same, looking only at the given vertices (and then at the corners of dropped faces): for a
/// face list where only those vertices can have more than one fan.
size_t dropPinchedFans(std::vector<Eigen::Vector3i>& faces, size_t num_vertices, std::vector<int> candidates);

/// Mean and maximum distance [m] from sample points to a reference surface.
struct SurfaceDistance {
  double mean_m = 0.0;
  double max_m = 0.0;
  size_t samples = 0;
};

/// Distances of the given points to the reference mesh's triangles (exact point-triangle distance
/// over a grid of the reference triangles).
SurfaceDistance distanceToSurface(const std::vector<Eigen::Vector3f>& samples, const TriangleMesh& reference);

/// Sample points on a mesh's faces: each face's centroid and the midpoints between the centroid and
/// its corners (4 per face).
std::vector<Eigen::Vector3f> sampleFaces(const TriangleMesh& mesh);

/// Per-vertex normals of a mesh: area-weighted sums of its face normals, normalized (zero for a
/// vertex without faces).
std::vector<Eigen::Vector3f> vertexNormalsFromFaces(const TriangleMesh& mesh);

}  // namespace mesher
}  // namespace scanstop
