#pragma once
/// Mesh decimation by quadric edge collapse (Garland and Heckbert 1997, "Surface simplification using
/// quadric error metrics") with a bound on the geometric error: the Marching Cubes mesh of the fused
/// map has a triangle per voxel face even on a flat wall; most of them can go without moving the
/// surface (issue #20: at most 1 M triangles for a room).
///
/// Each vertex carries the quadric of the planes of the faces it was made of (unweighted, unit
/// normals): the cost of placing a merged vertex at p is the mean of its squared distances to those
/// planes, so a collapse whose cost is at most max_error_m^2 leaves the vertex within max_error_m of
/// them in the root mean square. Collapses run cheapest first (a lazily updated bucket queue) until the next one would
/// pass the bound or the mesh is down to max_faces. A collapse is refused when it would change the
/// topology (the link condition), turn a face over or make it a sliver. Boundary vertices (holes
/// from unseen surfaces, the rim of the seen space) do not move: the mesh keeps its holes and its
/// outline exactly. A mesh that is not manifold at an edge keeps that edge's vertices as well.

#include <cstddef>
#include <vector>

#include "scanstop_common/cloud.h"

namespace scanstop {
namespace mesher {

/// Meshes with fewer faces are decimated on one thread.
constexpr size_t kMinFacesToSplit = 100000;

struct DecimateConfig {
  /// Bound on the root mean square distance of a merged vertex to the planes of the faces it
  /// replaces [m], [0, 0.1]. 0: no decimation. 0.002: a tenth of the fused map's voxel (0.02 m), at
  /// the averaged sensor noise; on room_10x8 and furnished_2 it leaves a quarter to a fifth of the
  /// Marching Cubes triangles and the mesh as near the world as before (docs/benchmarks.md).
  double max_error_m = 0.002;
  /// Stop once the mesh has at most this many faces (0: no target, only the error bound).
  size_t max_faces = 0;
  /// Smallest cosine between a face's normal before and after a collapse, [-1, 1]: 0.5 refuses a
  /// collapse that would turn a face by more than 60 degrees (a fold or a flipped face).
  double min_normal_cos = 0.5;
  /// Threads, [1, 2]. 2 (without max_faces): a mesh of at least kMinFacesToSplit faces is cut in two
  /// halves at the median x of its faces, each decimated on its own thread with the vertices on the
  /// cut pinned (the seam keeps its full resolution, the halves meet exactly); deterministic.
  int threads = 2;
  /// Throws ConfigError naming the field, its value and the allowed range.
  void validate() const;
};

struct DecimateStats {
  size_t faces_before = 0, faces_after = 0;
  size_t vertices_before = 0, vertices_after = 0;
  size_t collapses = 0;
  size_t refused = 0;          ///< collapses refused (topology, fold, sliver)
  size_t locked_vertices = 0;  ///< boundary, non-manifold or seam vertices that stayed where they were
  double max_error_m = 0.0;    ///< largest sqrt(cost) of an applied collapse [m]
  double seconds = 0.0;

  /// Adds another part's figures (counts and seconds summed, the largest error kept).
  void add(const DecimateStats& part);
};

/// Decimates the mesh in place (vertices, faces; normals recomputed from the faces, area-weighted,
/// when the mesh had normals). Faces keep their winding. Deterministic. Throws ConfigError for bad
/// settings, std::invalid_argument for a face with an index out of range.
/// `pinned` (by vertex index, may be shorter than the vertices or empty): vertices that stay where they
/// are as well (a slab's border band, so that the slabs still meet exactly).
DecimateStats decimateMesh(TriangleMesh& mesh, const DecimateConfig& config, const std::vector<char>& pinned = {});

}  // namespace mesher
}  // namespace scanstop
