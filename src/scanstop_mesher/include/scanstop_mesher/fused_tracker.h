#pragma once
/// The fused map kept up to date with a map directory during the mission (issue #20: "every
/// registered scan is integrated ... and rebuilt from the corrected poses when SLAM relaxes"):
/// each update() integrates the scans that appeared since the last one, and takes back and
/// integrates again the scans whose map pose moved (a relaxation, a re-registration). The mesh at the
/// end of a mission then needs only the last scan's integration and the meshing, not a pass over
/// every scan.
///
/// The far carving pass (FusedMapConfig::carve_far) needs every scan's voxels (a beam carves the
/// surfaces other scans made, also later ones): snapshot() runs it over all scans on a copy, on
/// map_config.threads threads, so the snapshot is integrateMapDirectory's field (up to float rounding
/// and the order of the scans).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "scanstop_common/pose.h"
#include "scanstop_mesher/fused_map.h"

namespace scanstop {
namespace mesher {

struct FusedTrackerConfig {
  /// A scan whose map pose moved farther than this [m], [0, 1], since it was integrated is integrated
  /// again. 0.005: a quarter of the default voxel.
  double repose_m = 0.005;
  /// ... or turned by more than this [deg], [0, 180]. 0.1: 3.5 mm at 2 m.
  double repose_deg = 0.1;
  /// Throws ConfigError naming the field.
  void validate() const;
};

/// What one update() did.
struct FusedTrackerUpdate {
  size_t integrated = 0;              ///< scans integrated for the first time
  size_t reintegrated = 0;            ///< scans taken back at their old pose and integrated at the new one
  size_t scans = 0;                   ///< scans in the fused map after the update
  std::vector<std::string> problems;  ///< scans (and lines) of the directory that could not be read, named
  double seconds = 0.0;
};

class FusedMapTracker {
 public:
  /// Throws ConfigError for bad settings (naming the field).
  FusedMapTracker(const FusedMapConfig& map_config, const FusedTrackerConfig& config = FusedTrackerConfig());

  /// Brings the fused map up to the map directory's poses.csv (openMapDirectory: strict about the
  /// directory, lenient about single scans, which are named in the result and left out). Throws
  /// IoError for a directory that cannot be read, GridBoundError when the grids would pass
  /// max_grid_mb (the map is then unusable: the caller falls back to integrateMapDirectory's slabs).
  FusedTrackerUpdate update(const std::string& dir);

  /// The fused map with the far carving pass over all scans (a copy; the tracker goes on). Reads the
  /// scan files again for it.
  FusedMap snapshot() const;
  /// The live map (the near integration only).
  const FusedMap& map() const { return map_; }
  size_t scans() const { return tracked_.size(); }

 private:
  struct Tracked {
    Pose2D pose;
    Eigen::Vector3d sensor_origin;
    std::string file;
  };
  FusedTrackerConfig config_;
  FusedMap map_;
  std::string dir_;  ///< the map directory of the last update
  std::map<uint32_t, Tracked> tracked_;
};

}  // namespace mesher
}  // namespace scanstop
