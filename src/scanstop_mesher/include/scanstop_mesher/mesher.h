#pragma once
/// The meshing pipeline around Ball Pivoting: input points (a cloud file or the SLAM map
/// directory), optional voxel downsampling, normals (given, or estimated and oriented towards the
/// scanner position each point was seen from), automatic radii, reconstruction, checks.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/ball_pivoting.h"
#include "scanstop_mesher/mesh_analysis.h"

namespace scanstop {
namespace mesher {

/// Points to mesh: with normals, or with the scanner position each point was measured from.
struct ScanPoints {
  std::vector<Eigen::Vector3f> points;   ///< [m]
  std::vector<Eigen::Vector3f> normals;  ///< unit normals (NaN = none usable), or empty
  std::vector<uint32_t> view;            ///< per point: index into origins (empty when normals are given)
  std::vector<Eigen::Vector3f> origins;  ///< scanner positions [m], same frame as the points
  size_t size() const { return points.size(); }
};

/// The scans of a map directory (scanstop_common/map_dir.h) in the map frame; each point's view is
/// its scan's scanner position, map_pose * sensor_origin. Throws IoError naming the bad file; with
/// `skipped` given, a scan file that cannot be read is skipped instead and its problem (naming the
/// file) appended there (IoError still when no scan is left).
ScanPoints loadMapDirectory(const std::string& dir, std::vector<std::string>* skipped = nullptr);

/// A map directory opened for reading, strictly (loadMapDirectory, integrateMapDirectory): creates
/// nothing; throws IoError naming the file for a missing poses.csv, any problem of the directory
/// (with `skipped` given, its problems are appended there instead) or a map without scans.
std::unique_ptr<const MapDirectory> openMapDirectory(const std::string& dir, std::vector<std::string>* skipped);

/// Where a mesh may be written: `path` (relative ones are taken relative to allowed_dir) resolved
/// to an absolute path whose directory exists and lies inside allowed_dir (after resolving '..',
/// '.' and symbolic links), ending in .stl or .ply. Throws ConfigError naming the path and what is
/// wrong (outside the directory, no such directory, a directory, wrong extension, empty).
std::string resolveOutputPath(const std::string& path, const std::string& allowed_dir);

/// Why these points cannot be meshed as given, or "": none, or a coordinate beyond max_abs_m
/// (absurd: it would blow up the neighbour grid). Names the first bad point.
std::string pointsProblem(const ScanPoints& points, double max_abs_m);

/// A cloud's finite points; its normals when it has them, else the viewpoint for all points.
ScanPoints fromCloud(const PointCloud& cloud, const Eigen::Vector3f& viewpoint);

/// One point per occupied voxel of edge voxel_m [m]: the centroid, the normalized mean normal (when
/// normals are given) and the view of the voxel's first point. voxel_m <= 0 returns the input.
ScanPoints voxelDownsample(const ScanPoints& in, double voxel_m);

/// Mean distance [m] to the nearest other point, over up to max_samples evenly spread points
/// (0 when fewer than two points).
double meanSpacing(const std::vector<Eigen::Vector3f>& points, size_t max_samples = 20000);

/// The automatic radii for a mean point spacing [m]: 1.25, 2 and 3 times it.
std::vector<double> automaticRadii(double spacing_m);

/// Estimates each point's normal from the principal axes of its neighbours within radius_m [m]
/// and turns it towards the point's scanner position. A point with fewer than min_neighbors
/// neighbours, a line-like neighbourhood, or a normal perpendicular to its view direction gets
/// NaN (it will be skipped, not guessed). Returns the number of usable normals.
/// With project = true each point with a usable normal is also moved onto its neighbourhood's
/// plane (removes range noise across the surface; thesis 8: the map accumulates every scan's noise).
size_t estimateNormals(ScanPoints& pts, double radius_m, int min_neighbors, bool project = false);

/// Pipeline settings.
struct MesherConfig {
  std::vector<double>
      radii_m;           ///< increasing ball radii [m], each in (0, 10], at most 32; empty = automaticRadii(spacing)
  double voxel_m = 0.0;  ///< voxel edge for downsampling [m], [0, 10]; 0 = none
  double normal_radius_m = 0.0;  ///< neighbourhood for normal estimation [m]; 0 = 3 x spacing
  int normal_min_neighbors = 5;  ///< neighbours a normal needs
  bool smooth = true;            ///< move points onto their local plane when estimating normals
  /// Checks the values; throws ConfigError naming the field.
  void validate() const;
};

/// Result of a meshing run.
struct MesherResult {
  TriangleMesh mesh;
  BpaStats stats;
  MeshTopology topology;
  size_t input_points = 0;  ///< points given
  size_t points = 0;        ///< points that entered the reconstruction (after voxels, with a normal)
  double spacing_m = 0.0;   ///< mean point spacing after downsampling
  std::vector<double> radii_m;
  double seconds = 0.0;          ///< wall time of the whole pipeline
  double prepare_seconds = 0.0;  ///< wall time of voxels, spacing and normals
  double bpa_seconds = 0.0;      ///< wall time of the Ball Pivoting passes
};

/// Runs the pipeline. Throws ConfigError for bad settings, std::runtime_error when there is nothing
/// to mesh (no point with a usable normal).
MesherResult buildMesh(const ScanPoints& input, const MesherConfig& config);

/// Parses "r1,r2,..." (metres, increasing, positive); throws ConfigError naming the bad item.
std::vector<double> parseRadii(const std::string& text);

}  // namespace mesher
}  // namespace scanstop
