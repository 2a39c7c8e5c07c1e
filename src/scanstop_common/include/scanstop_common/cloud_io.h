#pragma once
/// Point-cloud and mesh files: PCD (via PCL), PLY (ASCII and binary) and XYZ text.
///
/// Every reader throws IoError naming the file and the problem; every writer is atomic
/// (temporary file, fsync, rename). NaN points survive a round trip in every format.

#include <string>
#include <vector>

#include "scanstop_common/cloud.h"

namespace scanstop {

/// Coordinates farther from the origin than this on any axis (or infinite) are refused by the readers
/// of clouds, meshes and STL worlds (issue #22 class 3: one point or vertex at 1e30 m made a grid
/// overflow or a tool compute on nonsense). 100 km: far beyond any building. NaN points are kept
/// (organized clouds mark missing returns with them).
constexpr float kMaxFileCoordinateM = 1e5f;

/// "point 7 (1e+30, 0, 0) lies beyond the 100000 m coordinate limit" for the first such point of
/// `points` (`what` names the element: "point", "vertex"), or "" when there is none.
std::string coordinateProblem(const std::vector<Eigen::Vector3f>& points, const char* what = "point");

/// Reads a cloud, choosing the format from the extension (.pcd, .ply, .xyz/.txt).
/// PLY and PCD normals (nx ny nz / normal_x normal_y normal_z) and PCD "range" are kept;
/// PCD organization (width x height) is kept. A point beyond kMaxFileCoordinateM is an IoError.
PointCloud readCloud(const std::string& path);

/// Writes a cloud in the format given by the extension (.pcd binary, .ply binary, .xyz).
void writeCloud(const std::string& path, const PointCloud& cloud);

/// Reads a PCD file (ascii, binary, binary_compressed; any numeric field types). The header is checked
/// before PCL reads the file: entries, their order and consistency, and that the data section is complete.
PointCloud readPcd(const std::string& path);
/// The header and size check of readPcd alone (cheap: no point is read). Returns an empty string when
/// the file passes, else the problem ("empty file", "truncated PCD: ...", "not a valid PCD file: ...").
std::string pcdFileProblem(const std::string& path);
void writePcd(const std::string& path, const PointCloud& cloud);

/// Reads a PLY file's vertices (x y z, optional nx ny nz) and faces (vertex_indices or vertex_index).
/// Other elements and properties are skipped. ASCII, binary_little_endian and binary_big_endian.
TriangleMesh readPly(const std::string& path);
/// Parses PLY content held in memory; `name` is used in error messages.
TriangleMesh parsePly(const std::string& data, const std::string& name);
/// Reads a PLY file as a cloud (its vertices and normals; faces ignored).
PointCloud readPlyCloud(const std::string& path);
/// Writes vertices (+ normals when present) and faces (when present) as PLY.
void writePly(const std::string& path, const TriangleMesh& mesh, bool binary = true);
void writePlyCloud(const std::string& path, const PointCloud& cloud, bool binary = true);

/// XYZ text: one point per line, "x y z" or "x y z nx ny nz"; '#' starts a comment.
PointCloud readXyz(const std::string& path);
/// Parses XYZ text held in memory; `name` is used in error messages.
PointCloud parseXyz(const std::string& data, const std::string& name);
void writeXyz(const std::string& path, const PointCloud& cloud);

/// Reads a mesh by extension: .stl (soup) or .ply (indexed). A vertex beyond kMaxFileCoordinateM is an IoError.
TriangleMesh readMesh(const std::string& path);
/// Writes a mesh by extension: .stl (binary) or .ply (binary, with normals when present).
void writeMesh(const std::string& path, const TriangleMesh& mesh);

}  // namespace scanstop
