#include "scanstop_mission/run_directory.h"

#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>

#include "scanstop_common/file_util.h"

namespace scanstop {
namespace mission {
namespace {

const char* const kWhatToDo =
    "use a new run_dir (the launch's default is per world: ~/scanstop_runs/<world>) or delete this one to start "
    "afresh there";

bool exists(const std::string& path) {
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// mkdir -p; returns the errno of the first failure (0 on success).
int makeDirectories(const std::string& path) {
  for (size_t pos = 1; pos <= path.size(); ++pos) {
    if (pos != path.size() && path[pos] != '/') continue;
    const std::string prefix = path.substr(0, pos);
    if (::mkdir(prefix.c_str(), 0755) != 0 && errno != EEXIST) return errno;
  }
  return 0;
}

/// The map's poses.csv has a scan line, or the mission state lists a scan (a state that does not parse
/// counts as holding scans: the mission repairs it from the map, and nothing is set aside unread).
bool holdsScans(const std::string& dir) {
  std::ifstream poses(dir + "/map/poses.csv");
  std::string line;
  for (int n = 0; std::getline(poses, line); ++n)
    if (n > 0 && !line.empty()) return true;
  if (!exists(dir + "/mission_state.yaml")) return false;
  try {
    const YAML::Node root = YAML::LoadFile(dir + "/mission_state.yaml");
    return !root.IsMap() || !root["scans"] || !root["scans"].IsSequence() || root["scans"].size() > 0;
  } catch (const std::exception&) {
    return true;
  }
}

std::string kindOf(const struct stat& st) {
  if (S_ISREG(st.st_mode)) return "a regular file";
  if (S_ISLNK(st.st_mode)) return "a symbolic link";
  if (S_ISFIFO(st.st_mode)) return "a FIFO";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "a device";
  return "not a directory";
}

std::string nowUtc() {
  char buf[32];
  const std::time_t t = std::time(nullptr);
  std::tm tm;
  gmtime_r(&t, &tm);
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

void RunIdentity::save(const std::string& path) const {
  YAML::Emitter out;
  out << YAML::Comment(
             "scanstop run directory: what this run is (written when it began; a resume with other values "
             "is refused)")
      << YAML::Newline;
  out << YAML::BeginMap;
  for (const auto& [key, value] : fields) out << YAML::Key << key << YAML::Value << YAML::DoubleQuoted << value;
  out << YAML::EndMap;
  writeFileAtomic(path, std::string(out.c_str()) + "\n");
}

RunIdentity RunIdentity::load(const std::string& path) {
  const std::string text = readFile(path);
  RunIdentity id;
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) throw std::runtime_error("expected a YAML map of field: value");
    for (const auto& kv : root)
      id.fields[kv.first.as<std::string>()] = kv.second.IsNull() ? "" : kv.second.as<std::string>();
  } catch (const std::exception& e) {
    throw IoError(path, std::string("not a run identity: ") + e.what());
  }
  return id;
}

std::string identityDifferences(const RunIdentity& recorded, const RunIdentity& now) {
  std::string out;
  for (const auto& [key, value] : recorded.fields) {
    if (key == "created") continue;  // when, not what
    const auto it = now.fields.find(key);
    const std::string current = it == now.fields.end() ? "" : it->second;
    if (current == value) continue;
    out += (out.empty() ? "" : "; ") + key + " is '" + value + "' there, '" + current + "' now";
  }
  return out;
}

std::string fileFingerprint(const std::string& path) {
  const std::string data = readFile(path);
  uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : data) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

RunDirectory::RunDirectory(const std::string& path, const RunIdentity& identity) : path_(path) {
  if (path_.empty()) throw RunDirectoryError("(empty)", "the run directory path is empty");
  while (path_.size() > 1 && path_.back() == '/') path_.pop_back();
  struct stat st;
  if (::stat(path_.c_str(), &st) == 0) {
    if (!S_ISDIR(st.st_mode))
      throw RunDirectoryError(path_,
                              "the run directory exists but is " + kindOf(st) +
                                  ", not a directory: give run_dir a directory (or a path that does not exist yet)");
  } else {
    const int err = makeDirectories(path_);
    if (err != 0)
      throw RunDirectoryError(path_, std::string("cannot create the run directory (") + std::strerror(err) + ")");
    created_ = true;
  }
  if (::access(path_.c_str(), W_OK | X_OK) != 0)
    throw RunDirectoryError(path_, std::string("the run directory is not writable (") + std::strerror(errno) + ")");

  bool has_mission = exists(path_ + "/mission_state.yaml") || exists(path_ + "/map/poses.csv");
  if (has_mission && !holdsScans(path_)) {
    // A mission that ended before its first scan (a start-up error: a bad start pose, a missing world;
    // SLAM may have written a poses.csv without a scan line) holds nothing to protect: the corrected
    // launch starts afresh here. Its state is kept aside.
    if (exists(path_ + "/mission_state.yaml")) {
      set_aside_ = path_ + "/mission_state.yaml.unstarted";
      if (std::rename((path_ + "/mission_state.yaml").c_str(), set_aside_.c_str()) != 0)
        throw RunDirectoryError(path_, std::string("cannot set aside mission_state.yaml of a mission that took no "
                                                   "scan (") +
                                           std::strerror(errno) + ")");
    }
    has_mission = false;
  }
  RunIdentity recorded;
  bool have_recorded = false;
  if (exists(identityPath())) {
    recorded = RunIdentity::load(identityPath());
    have_recorded = true;
  } else if (has_mission && exists(path_ + "/mission_state.yaml")) {
    // A run directory of an earlier version: its mission state names the world.
    try {
      const YAML::Node root = YAML::LoadFile(path_ + "/mission_state.yaml");
      if (root.IsMap() && root["world"] && !root["world"].as<std::string>().empty()) {
        recorded.fields["world"] = root["world"].as<std::string>();
        have_recorded = true;
      }
    } catch (const std::exception&) {
      // corrupt: the mission repairs it from the map; nothing to compare against
    }
  }
  if (has_mission && have_recorded) {
    const std::string diff = identityDifferences(recorded, identity);
    if (!diff.empty())
      throw RunDirectoryError(path_, "the run directory holds another run's mission (" + diff + "); refusing to mix " +
                                         "them: " + kWhatToDo);
    resumed_ = true;
    if (exists(identityPath())) return;
  } else if (has_mission) {
    resumed_ = true;  // an earlier version's mission without a world to compare: adopt it
  }
  RunIdentity written = identity;
  written.fields["created"] = nowUtc();
  written.save(identityPath());
}

}  // namespace mission
}  // namespace scanstop
