#pragma once
/// The map directory: the SLAM map on disk, shared by icp_slam_node (writes it after every scan),
/// the explorer, the mesher, the mission and the offline tools (read it).
///
/// Layout:
///   <dir>/poses.csv            one line per scan (header line first), rewritten atomically per scan
///   <dir>/scans/scan_NNNN.pcd  the scan's finite points in the base_link frame at scan time [m]
///   <dir>/pose_history.csv     (after a global relaxation moved poses: updatePoses) every map pose
///                              that was replaced, header "index,revision,map_x,map_y,map_yaw"
///   <dir>/poses_journal.csv    append-only ledger of every poses.csv line ever written (same header
///                              and columns; a later line of an index supersedes an earlier one),
///                              fsync'd before poses.csv is rewritten. A scan whose poses.csv line is
///                              missing or corrupt is restored from it on loading (issue #22 class 8).
/// A scan's points in the map frame are map_pose.toIsometry3f() * p.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/pose.h"

namespace scanstop {

/// One scan's entry in poses.csv.
struct MapScanInfo {
  uint32_t index = 0;
  std::string file;      ///< relative to the map directory, e.g. "scans/scan_0003.pcd"
  double stamp_s = 0.0;  ///< scan time [s]
  Pose2D map_pose;       ///< corrected pose of base_link in the map frame
  Pose2D odom_pose;      ///< odometry pose of base_link in the odom frame
  Eigen::Vector3d sensor_origin = Eigen::Vector3d::Zero();  ///< scanner centre in base_link [m]
  bool converged = true;  ///< false: registration failed, the odometry-based pose was kept
  uint32_t iterations = 0;
  uint32_t correspondences = 0;
  double rms_m = 0.0;
  double overlap = 0.0;
};

/// Something wrong in a map directory found while loading it: the file and what was wrong.
struct MapProblem {
  std::string path;     ///< the bad file (poses.csv or a scan file), absolute when the directory is
  std::string problem;  ///< what was wrong and what the loader did, e.g. "line 4: ...; line skipped"
  /// Nothing was lost: the scan of this bad poses.csv line came back from poses_journal.csv (and the
  /// note of that restoration itself).
  bool repaired = false;
  std::string message() const { return path + ": " + problem; }
  /// The problem without the loader's note of what it did ("; line skipped", "; scan 2 skipped",
  /// "; not loaded"): what a reader that refuses the map says.
  std::string withoutSkipNote() const;
};

/// Reads and appends to a map directory. Files are written atomically (temporary file, fsync, rename).
/// Loading validates each line of poses.csv and each scan file: a bad line or a missing, empty,
/// truncated or corrupt scan file is reported in problems() and that scan is skipped; all other scans
/// are kept. Nothing in a corrupt directory makes the loader throw or crash.
/// The scan ledger: poses.csv and the scan files are kept in step through poses_journal.csv. Writers
/// write the scan file, then its line to the journal, then poses.csv. On loading, an index whose
/// poses.csv line is missing or did not parse but whose journal line names its scan file is restored
/// from the journal (reported in problems() as "restored from poses_journal.csv"), so a corrupt
/// poses.csv loses no scan and the next rewrite of poses.csv puts the line back. A scan file that no
/// line of either file names is reported (an append interrupted before its line was written).
class MapDirectory {
 public:
  /// Opens (creating it when missing) the directory; loads an existing poses.csv, skipping and
  /// reporting bad lines and scans whose file fails the check (problems()). Throws IoError only when
  /// the directory cannot be created or poses.csv exists but cannot be read.
  explicit MapDirectory(const std::string& dir);

  const std::string& dir() const { return dir_; }
  /// The loadable scans in index order. Indices have gaps where scans were skipped.
  const std::vector<MapScanInfo>& scans() const { return scans_; }
  size_t size() const { return scans_.size(); }
  /// What was wrong with the directory when it was loaded (empty for a healthy map).
  const std::vector<MapProblem>& problems() const { return problems_; }
  /// The index the next appended scan must have: one past every index poses.csv mentions, also on
  /// skipped lines and for skipped scans, and whose scans/scan_NNNN.pcd no line names, so the file of a
  /// listed scan is never overwritten. Scan files
  /// that poses.csv does not list (an append interrupted before poses.csv was written) are reported and
  /// replaced by the scan that gets their index. Equals size() for a healthy map.
  uint32_t nextIndex() const { return next_index_; }

  /// Writes the cloud (base_link frame; NaN points dropped) as scans/scan_NNNN.pcd, then poses.csv.
  /// info.index must equal nextIndex(); info.file is filled in. Throws IoError. Rewriting poses.csv
  /// drops lines that could not be parsed and keeps the lines of scans whose file was bad.
  void append(MapScanInfo info, const PointCloud& cloud_base);
  /// Replaces the poses of the loaded scan with info.index (e.g. after a re-registration) and rewrites
  /// poses.csv. Throws IoError when there is no such scan.
  void updateInfo(const MapScanInfo& info);

  /// Replaces the map poses of loaded scans (a global relaxation moved them), given as (scan index,
  /// new map pose) pairs, and rewrites poses.csv atomically. First the poses being replaced are
  /// appended to pose_history.csv (rewritten atomically too) as revision poseRevision() + 1, so no
  /// pose is ever lost: an interruption in between leaves a history line whose pose still stands.
  /// Pairs whose pose equals the stored one exactly are left out of the history. Returns the new
  /// revision (the old one when nothing changed). Throws IoError, changing nothing in memory, for
  /// an index that is not a loaded scan, a non-finite pose or a failed write.
  uint32_t updatePoses(const std::vector<std::pair<uint32_t, Pose2D>>& poses);
  /// The number of the last updatePoses() revision (also from pose_history.csv when loaded; 0: none).
  uint32_t poseRevision() const { return pose_revision_; }
  /// Absolute path of pose_history.csv.
  std::string poseHistoryPath() const { return dir_ + "/pose_history.csv"; }

  /// Loads the scan at position i of scans() in the base_link frame. Throws IoError naming the file.
  PointCloud loadScan(size_t i) const;
  /// Loads the scan at position i transformed into the map frame.
  PointCloud loadScanInMap(size_t i) const;

  /// Absolute path of poses.csv.
  std::string posesPath() const { return dir_ + "/poses.csv"; }
  /// Absolute path of poses_journal.csv (the ledger of every poses.csv line written).
  std::string journalPath() const { return dir_ + "/poses_journal.csv"; }
  /// The indices whose line was restored from the journal when the directory was loaded.
  const std::vector<uint32_t>& restored() const { return restored_; }

 private:
  void load();
  void setNextIndex(uint32_t candidate);
  void writePoses() const;
  /// Writes rows to the journal (fsync'd); creates it, seeded with every line of poses.csv, when missing.
  void writeJournal(const std::vector<MapScanInfo>& rows) const;
  /// Adds to `all` the indices poses.csv lost, from the journal (see the class comment).
  void restoreFromJournal(std::vector<MapScanInfo>& all, long& largest);
  std::string dir_;
  std::vector<MapScanInfo> scans_;
  std::vector<MapScanInfo> skipped_;  ///< parsed lines whose scan file was bad (kept in poses.csv)
  std::vector<MapProblem> problems_;
  std::vector<std::string> named_files_;  ///< every scan file a line of poses.csv names
  uint32_t next_index_ = 0;
  uint32_t pose_revision_ = 0;
  std::vector<uint32_t> restored_;
};

/// Transforms every point of a cloud (NaN stays NaN).
PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3f& T_target_source);

}  // namespace scanstop
