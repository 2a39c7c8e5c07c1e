#pragma once
/// The run directory (issue 22, "lose nothing"): everything of one mission (its state, the SLAM map,
/// the simulation's state, the report) lives in one directory, and a mission resumes from it. A
/// directory must therefore know what it belongs to: when a run begins in it, its identity (world,
/// world file, start pose, the simulation's error profile and seed, planes per scan) is written to
/// <run_dir>/run_identity.yaml, and a later run with a different identity is refused, naming what
/// differs and what to do, instead of registering another world's scans into this map. ROS-free.

#include <map>
#include <stdexcept>
#include <string>

#include "scanstop_common/error.h"

namespace scanstop {
namespace mission {

/// What a run is: field -> value (e.g. world -> room_10x8). Fields are compared as text.
struct RunIdentity {
  std::map<std::string, std::string> fields;

  /// Writes the identity as YAML, atomically. Throws IoError.
  void save(const std::string& path) const;
  /// Reads a saved identity; throws IoError naming the file when it is not one.
  static RunIdentity load(const std::string& path);
};

/// The fields that differ, as "world is 'room_10x8' there, 'corridor' now; seed ...": every field
/// recorded in `recorded` compared with `now` (a field missing in `now` counts as empty; a field the
/// recording lacks, e.g. one added by a later version, is not compared). Empty when they agree.
std::string identityDifferences(const RunIdentity& recorded, const RunIdentity& now);

/// FNV-1a 64 of a file's bytes as 16 hex digits: the world file's fingerprint (the same world at
/// another path is the same world; an edited file is another). Throws IoError naming the file when
/// it is missing or unreadable.
std::string fileFingerprint(const std::string& path);

/// The run directory belongs to another run (different identity), or is not a directory, or cannot
/// be created. what() names the directory, the cause and what to do.
class RunDirectoryError : public IoError {
 public:
  using IoError::IoError;
};

class RunDirectory {
 public:
  /// Opens `path` for a run of `identity`:
  ///  - path missing: created (with its parents), the identity written;
  ///  - path exists but is not a directory, or cannot be created/written: RunDirectoryError;
  ///  - path holds no mission yet (no mission_state.yaml, no map/poses.csv): the identity is (re)written;
  ///  - path holds a mission of the same identity: resumed() is true;
  ///  - path holds a mission of another identity: RunDirectoryError naming the differences;
  ///  - path holds a mission that took no scan (it ended at start-up, e.g. on a bad start pose): its
  ///    mission_state.yaml is renamed to mission_state.yaml.unstarted (setAside()) and the run starts
  ///    afresh, so that the corrected launch is not refused as another run.
  /// A directory of an earlier version (a mission but no run_identity.yaml) is checked by the world
  /// its mission_state.yaml names; when it agrees the identity is recorded.
  RunDirectory(const std::string& path, const RunIdentity& identity);

  const std::string& path() const { return path_; }
  std::string identityPath() const { return path_ + "/run_identity.yaml"; }
  /// The directory held a mission of this identity (it will be resumed).
  bool resumed() const { return resumed_; }
  /// The directory was created by this run.
  bool created() const { return created_; }
  /// Where the state of a mission that took no scan was moved ("" when none was).
  const std::string& setAside() const { return set_aside_; }

 private:
  std::string path_;
  bool resumed_ = false;
  bool created_ = false;
  std::string set_aside_;
};

}  // namespace mission
}  // namespace scanstop
