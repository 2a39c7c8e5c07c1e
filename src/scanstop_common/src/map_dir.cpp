#include "scanstop_common/map_dir.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace {

const char* const kHeader =
    "index,file,stamp_s,map_x,map_y,map_yaw,odom_x,odom_y,odom_yaw,sensor_x,sensor_y,sensor_z,"
    "converged,iterations,correspondences,rms_m,overlap";
constexpr size_t kColumns = 17;
const char* const kHistoryHeader = "index,revision,map_x,map_y,map_yaw";
constexpr double kMaxIndex = 9999999.0;  // scan_%04u names sort up to 7 digits

/// A relative path without empty or "." components ("scans//./a.pcd" -> "scans/a.pcd"); "" when none is left.
std::string lexicallyNormal(const std::string& path) {
  std::string out;
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find('/', start), path.size());
    const std::string part = path.substr(start, end - start);
    if (!part.empty() && part != ".") out += (out.empty() ? "" : "/") + part;
    start = end + 1;
  }
  return out;
}

/// Pose coordinates beyond this are refused when read or appended (issue #22 class 3: one pose 100 km
/// away made a tool's grid grow to gigabytes). 10 km is far beyond any building the robot maps.
constexpr double kMaxPoseCoordinateM = 10000.0;

/// Why a pose is refused, or empty.
std::string poseProblem(const Pose2D& p, const char* what) {
  if (!p.isFinite()) return std::string(what) + " " + p.toString() + " is not finite";
  if (std::abs(p.x) > kMaxPoseCoordinateM || std::abs(p.y) > kMaxPoseCoordinateM)
    return std::string(what) + " " + p.toString() + " is beyond the 10000 m pose limit (|x|, |y| <= 10 km)";
  return {};
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(item);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

/// Parses one poses.csv line; throws std::invalid_argument saying what is wrong.
MapScanInfo parseLine(const std::string& line) {
  const std::vector<std::string> f = splitCsv(line);
  const auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (f.size() != kColumns)
    fail("expected " + std::to_string(kColumns) + " comma-separated values, found " + std::to_string(f.size()));
  std::vector<double> v(kColumns, 0.0);
  for (size_t i = 0; i < kColumns; ++i) {
    if (i == 1) continue;
    char* end = nullptr;
    v[i] = std::strtod(f[i].c_str(), &end);
    if (f[i].empty() || *end != '\0' || !std::isfinite(v[i]))
      fail("column " + std::to_string(i + 1) + " ('" + f[i].substr(0, 40) + "') is not a finite number");
  }
  // Integer columns: index, converged (0/1), iterations, correspondences (a plain cast of a negative or
  // huge double would be undefined behaviour).
  for (size_t i : {size_t{0}, size_t{12}, size_t{13}, size_t{14}}) {
    const double max = i == 0 ? kMaxIndex : i == 12 ? 1.0 : 4294967295.0;
    if (v[i] < 0.0 || v[i] > max || v[i] != std::floor(v[i]))
      fail("column " + std::to_string(i + 1) + " ('" + f[i].substr(0, 40) + "') is not an integer from 0 to " +
           std::to_string(static_cast<uint64_t>(max)));
  }
  MapScanInfo info;
  info.index = static_cast<uint32_t>(v[0]);
  info.file = f[1];
  info.stamp_s = v[2];
  info.map_pose = Pose2D(v[3], v[4], v[5]);
  info.odom_pose = Pose2D(v[6], v[7], v[8]);
  info.sensor_origin = Eigen::Vector3d(v[9], v[10], v[11]);
  info.converged = v[12] != 0.0;
  info.iterations = static_cast<uint32_t>(v[13]);
  info.correspondences = static_cast<uint32_t>(v[14]);
  info.rms_m = v[15];
  info.overlap = v[16];
  for (const auto& pose : {std::make_pair(&info.map_pose, "map pose (columns 4-6)"),
                           std::make_pair(&info.odom_pose, "odometry pose (columns 7-9)")}) {
    const std::string problem = poseProblem(*pose.first, pose.second);
    if (!problem.empty()) fail(problem);
  }
  const bool control =
      std::any_of(info.file.begin(), info.file.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; });
  if (info.file.empty() || info.file.find("..") != std::string::npos || info.file[0] == '/' || control)
    fail("scan file name '" + info.file.substr(0, 40) + "' must be a relative path inside the map directory");
  // One spelling per file: "scans//a.pcd" and "./scans/a.pcd" name scans/a.pcd, so that the checks
  // against other lines' files (and append()'s own names) compare like with like.
  info.file = lexicallyNormal(info.file);
  if (info.file.empty()) fail("scan file name '" + f[1].substr(0, 40) + "' names no file");
  return info;
}

/// The index in the first column of a line that does not parse, when it is one.
bool leadingIndex(const std::string& line, uint32_t& index) {
  const size_t comma = line.find(',');
  const std::string first = line.substr(0, comma);
  if (first.empty() || first.size() > 7 || first.find_first_not_of("0123456789") != std::string::npos) return false;
  index = static_cast<uint32_t>(std::stoul(first));
  return true;
}

/// The file append() writes for a scan index.
std::string scanFileName(uint32_t index) {
  char name[32];
  std::snprintf(name, sizeof(name), "scans/scan_%04u.pcd", index);
  return name;
}

/// The scan files on disk named like the ones append() writes ("scan_NNNN.pcd"), sorted.
std::vector<std::string> scanFilesOnDisk(const std::string& scans_dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(scans_dir.c_str());
  if (!d) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.size() >= 13 && name.compare(0, 5, "scan_") == 0 && name.compare(name.size() - 4, 4, ".pcd") == 0 &&
        name.find_first_not_of("0123456789", 5) == name.size() - 4)
      names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

std::string formatLine(const MapScanInfo& s) {
  std::ostringstream out;
  out << std::setprecision(17) << s.index << ',' << s.file << ',' << s.stamp_s << ',' << s.map_pose.x << ','
      << s.map_pose.y << ',' << s.map_pose.yaw << ',' << s.odom_pose.x << ',' << s.odom_pose.y << ',' << s.odom_pose.yaw
      << ',' << s.sensor_origin.x() << ',' << s.sensor_origin.y() << ',' << s.sensor_origin.z() << ','
      << (s.converged ? 1 : 0) << ',' << s.iterations << ',' << s.correspondences << ',' << s.rms_m << ',' << s.overlap;
  return out.str();
}

/// Appends data to the file at path and fsyncs it (the journal is append-only: never rewritten).
/// A last line cut by a crash is ended first, so the new line is not glued onto it.
void appendFileSynced(const std::string& path, std::string data) {
  const int fd = ::open(path.c_str(), O_RDWR | O_APPEND | O_CLOEXEC);
  if (fd < 0) throw IoError(path, std::string("cannot open for appending: ") + std::strerror(errno));
  struct stat st;
  char last = '\n';
  if (::fstat(fd, &st) == 0 && st.st_size > 0 && ::pread(fd, &last, 1, st.st_size - 1) == 1 && last != '\n')
    data.insert(data.begin(), '\n');
  size_t written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(fd, data.data() + written, data.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      throw IoError(path, "write failed: " + why);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0)
    throw IoError(path, std::string("cannot flush to disk: ") + std::strerror(errno));
}

}  // namespace

std::string MapProblem::withoutSkipNote() const {
  const size_t semi = problem.rfind("; ");
  if (semi == std::string::npos) return problem;
  const std::string tail = problem.substr(semi + 2);
  const bool note = (tail.size() >= 7 && tail.compare(tail.size() - 7, 7, "skipped") == 0) || tail == "not loaded" ||
                    tail == "no scans loaded";
  return note ? problem.substr(0, semi) : problem;
}

MapDirectory::MapDirectory(const std::string& dir) : dir_(dir) {
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
  if (dir_.empty()) throw IoError(dir, "empty map directory name");
  makeDirectories(dir_);
  makeDirectories(dir_ + "/scans");
  load();
}

void MapDirectory::load() {
  const std::string poses = posesPath();
  long largest = -1;  // the largest index poses.csv mentions, also on lines that are skipped
  const auto note = [&largest](uint32_t index) { largest = std::max<long>(largest, index); };
  std::vector<MapScanInfo> all;                        // parsed lines, first of each index
  std::vector<size_t> first_line;                      // their line numbers
  std::vector<std::string> mentioned;                  // file column of skipped lines
  std::vector<std::pair<size_t, uint32_t>> bad_lines;  // (problem, index) of lines that did not parse
  struct stat st;
  const bool exists = ::stat(poses.c_str(), &st) == 0 || errno != ENOENT;
  if (exists && !S_ISREG(st.st_mode)) throw IoError(poses, "not a regular file");
  const std::string text = exists ? readFile(poses) : std::string();  // IoError when it cannot be read
  if (exists && text.empty()) problems_.push_back({poses, "empty file (no header line); no scans loaded"});
  std::istringstream in(text);
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 1 && line == kHeader) continue;
    if (line.empty()) continue;
    const std::string where = "line " + std::to_string(line_no) + ": ";
    MapScanInfo info;
    try {
      info = parseLine(line);
    } catch (const std::invalid_argument& e) {
      uint32_t index = 0;
      if (leadingIndex(line, index)) {
        note(index);
        bad_lines.emplace_back(problems_.size(), index);
      }
      const std::vector<std::string> columns = splitCsv(line);
      if (columns.size() > 1) mentioned.push_back(columns[1]);
      problems_.push_back(
          {poses, where + (line_no == 1 ? "not the scanstop poses header" : e.what()) + "; line skipped"});
      continue;
    }
    if (line_no == 1) problems_.push_back({poses, "line 1: the header is missing; read as a scan line"});
    note(info.index);
    const auto same = std::find_if(all.begin(), all.end(), [&](const MapScanInfo& s) { return s.index == info.index; });
    if (same != all.end()) {
      problems_.push_back({poses, where + "scan index " + std::to_string(info.index) + " already on line " +
                                      std::to_string(first_line[same - all.begin()]) + "; line skipped"});
      continue;
    }
    const auto same_file =
        std::find_if(all.begin(), all.end(), [&](const MapScanInfo& s) { return s.file == info.file; });
    if (same_file != all.end()) {
      problems_.push_back({poses, where + "file " + info.file + " already belongs to scan " +
                                      std::to_string(same_file->index) + " (line " +
                                      std::to_string(first_line[same_file - all.begin()]) + "); line skipped"});
      continue;
    }
    all.push_back(info);
    first_line.push_back(line_no);
  }
  restoreFromJournal(all, largest);
  for (const auto& [problem, index] : bad_lines)
    if (std::find(restored_.begin(), restored_.end(), index) != restored_.end()) problems_[problem].repaired = true;
  std::stable_sort(all.begin(), all.end(),
                   [](const MapScanInfo& a, const MapScanInfo& b) { return a.index < b.index; });
  for (const MapScanInfo& info : all) {
    const std::string path = dir_ + "/" + info.file;
    std::string problem;
    if (fileExtension(path) == "pcd") {
      problem = pcdFileProblem(path);
    } else {
      try {
        readCloud(path);
      } catch (const IoError& e) {
        problem = e.problem();
      }
    }
    if (problem.empty()) {
      scans_.push_back(info);
    } else {
      problems_.push_back({path, problem + "; scan " + std::to_string(info.index) + " skipped"});
      skipped_.push_back(info);
    }
  }
  // Scan files no line of poses.csv names: an append interrupted between the scan file and poses.csv
  // (or a line lost when a corrupt poses.csv was repaired).
  // They hold no pose; the scan with that index, when it comes, replaces them.
  for (const std::string& name : scanFilesOnDisk(dir_ + "/scans")) {
    const bool listed =
        std::any_of(all.begin(), all.end(), [&](const MapScanInfo& s) { return s.file == "scans/" + name; }) ||
        std::find(mentioned.begin(), mentioned.end(), "scans/" + name) != mentioned.end();
    if (!listed)
      problems_.push_back({dir_ + "/scans/" + name, "not listed in poses.csv (an interrupted append?); not loaded"});
  }
  // The next scan's file must not be one a line names (a line may name another index's file).
  for (const MapScanInfo& s : all) named_files_.push_back(s.file);
  named_files_.insert(named_files_.end(), mentioned.begin(), mentioned.end());
  setNextIndex(static_cast<uint32_t>(largest + 1));
  // The last relaxation's revision: the largest in pose_history.csv (lines that do not parse are
  // left alone; the history is only appended to).
  const std::string history = poseHistoryPath();
  if (::stat(history.c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
    std::istringstream h(readFile(history));
    while (std::getline(h, line)) {
      const std::vector<std::string> f = splitCsv(line);
      if (f.size() != 5 || f[1].empty() || f[1].size() > 9 || f[1].find_first_not_of("0123456789") != std::string::npos)
        continue;
      pose_revision_ = std::max<uint32_t>(pose_revision_, static_cast<uint32_t>(std::stoul(f[1])));
    }
  }
}

// The ledger: indices that poses.csv lost (a line that did not parse, a line cut off, an emptied file)
// come back from the journal's last line for them, when that line names the index's own scan file and
// no line of poses.csv names that file for another scan. They then go through the scan-file check like
// every other line. Journal lines that do not parse are reported and ignored.
// (A garbage line of poses.csv may name the file: that is the line being restored.)
void MapDirectory::restoreFromJournal(std::vector<MapScanInfo>& all, long& largest) {
  const std::string journal = journalPath();
  struct stat st;
  if (::stat(journal.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return;
  std::string text;
  try {
    text = readFile(journal);
  } catch (const IoError& e) {
    problems_.push_back({journal, std::string(e.problem()) + "; nothing restored from it"});
    return;
  }
  std::vector<std::pair<MapScanInfo, size_t>> latest;  // the last line of each index, with its line number
  std::istringstream in(text);
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line == kHeader) continue;
    MapScanInfo info;
    try {
      info = parseLine(line);
    } catch (const std::invalid_argument& e) {
      problems_.push_back({journal, "line " + std::to_string(line_no) + ": " + e.what() + "; line ignored"});
      continue;
    }
    const auto same =
        std::find_if(latest.begin(), latest.end(), [&](const auto& l) { return l.first.index == info.index; });
    if (same != latest.end())
      *same = {info, line_no};
    else
      latest.emplace_back(info, line_no);
  }
  const std::string poses = posesPath();
  for (const auto& entry : latest) {
    const MapScanInfo& info = entry.first;
    if (std::any_of(all.begin(), all.end(), [&](const MapScanInfo& s) { return s.index == info.index; })) continue;
    const std::string where = "scan " + std::to_string(info.index) + " has no valid line in poses.csv; ";
    if (info.file != scanFileName(info.index)) {
      problems_.push_back({journal, "line " + std::to_string(entry.second) + ": " + where + "the journal line names " +
                                        info.file + ", not " + scanFileName(info.index) + "; not restored"});
      continue;
    }
    const auto owner = std::find_if(all.begin(), all.end(), [&](const MapScanInfo& s) { return s.file == info.file; });
    if (owner != all.end()) {
      problems_.push_back({journal, "line " + std::to_string(entry.second) + ": " + where + "its file " + info.file +
                                        " belongs to scan " + std::to_string(owner->index) +
                                        " in poses.csv; not restored"});
      continue;
    }
    problems_.push_back({poses, where + "restored from poses_journal.csv line " + std::to_string(entry.second), true});
    all.push_back(info);
    restored_.push_back(info.index);
    largest = std::max<long>(largest, info.index);
  }
}

void MapDirectory::writeJournal(const std::vector<MapScanInfo>& rows) const {
  const std::string journal = journalPath();
  struct stat st;
  std::string out;
  for (const MapScanInfo& s : rows) out += formatLine(s) + "\n";
  if (::stat(journal.c_str(), &st) == 0) {
    appendFileSynced(journal, out);
    return;
  }
  // A map written before the journal existed: seed it with every line poses.csv holds.
  std::vector<MapScanInfo> all = scans_;
  all.insert(all.end(), skipped_.begin(), skipped_.end());
  std::sort(all.begin(), all.end(), [](const MapScanInfo& a, const MapScanInfo& b) { return a.index < b.index; });
  std::string seed = std::string(kHeader) + "\n";
  for (const MapScanInfo& s : all) seed += formatLine(s) + "\n";
  writeFileAtomic(journal, seed + out);
}

void MapDirectory::setNextIndex(uint32_t candidate) {
  next_index_ = candidate;
  while (std::find(named_files_.begin(), named_files_.end(), scanFileName(next_index_)) != named_files_.end())
    ++next_index_;
}

void MapDirectory::append(MapScanInfo info, const PointCloud& cloud_base) {
  if (info.index != next_index_)
    throw IoError(posesPath(), "cannot append scan " + std::to_string(info.index) + ": the next index is " +
                                   std::to_string(next_index_) + " (" + std::to_string(scans_.size()) +
                                   " scans loaded)");
  for (const auto& pose :
       {std::make_pair(&info.map_pose, "map pose"), std::make_pair(&info.odom_pose, "odometry pose")}) {
    const std::string problem = poseProblem(*pose.first, pose.second);
    if (!problem.empty())
      throw IoError(posesPath(), "cannot append scan " + std::to_string(info.index) + ": " + problem);
  }
  info.file = scanFileName(info.index);
  writeCloud(dir_ + "/" + info.file, removeNonFinite(cloud_base));
  writeJournal({info});  // before poses.csv: a line poses.csv loses comes back from here
  scans_.push_back(info);
  try {
    writePoses();
  } catch (...) {
    scans_.pop_back();
    throw;
  }
  named_files_.push_back(info.file);
  setNextIndex(info.index + 1);
}

void MapDirectory::updateInfo(const MapScanInfo& info) {
  const auto it =
      std::find_if(scans_.begin(), scans_.end(), [&](const MapScanInfo& s) { return s.index == info.index; });
  if (it == scans_.end())
    throw IoError(posesPath(), "cannot update scan " + std::to_string(info.index) + ": no such scan");
  const MapScanInfo old = *it;
  MapScanInfo updated = info;
  updated.file = old.file;
  writeJournal({updated});
  *it = updated;
  try {
    writePoses();
  } catch (...) {
    *it = old;
    throw;
  }
}

uint32_t MapDirectory::updatePoses(const std::vector<std::pair<uint32_t, Pose2D>>& poses) {
  std::vector<MapScanInfo> updated = scans_;
  std::ostringstream old_lines;
  old_lines << std::setprecision(17);
  const uint32_t revision = pose_revision_ + 1;
  bool changed = false;
  for (const auto& entry : poses) {
    const uint32_t index = entry.first;
    const Pose2D& pose = entry.second;
    const auto it =
        std::find_if(updated.begin(), updated.end(), [&](const MapScanInfo& s) { return s.index == index; });
    if (it == updated.end())
      throw IoError(posesPath(), "cannot update the pose of scan " + std::to_string(index) + ": no such scan");
    if (!pose.isFinite())
      throw IoError(posesPath(),
                    "cannot update scan " + std::to_string(index) + " to the non-finite pose " + pose.toString());
    if (!poseProblem(pose, "pose").empty())
      throw IoError(posesPath(), "cannot update scan " + std::to_string(index) + ": " + poseProblem(pose, "pose"));
    if (it->map_pose.x == pose.x && it->map_pose.y == pose.y && it->map_pose.yaw == pose.yaw) continue;
    old_lines << index << ',' << revision << ',' << it->map_pose.x << ',' << it->map_pose.y << ',' << it->map_pose.yaw
              << '\n';
    it->map_pose = pose;
    changed = true;
  }
  if (!changed) return pose_revision_;
  std::vector<MapScanInfo> moved;
  for (const MapScanInfo& s : updated) {
    const auto before =
        std::find_if(scans_.begin(), scans_.end(), [&](const MapScanInfo& o) { return o.index == s.index; });
    if (before->map_pose.x != s.map_pose.x || before->map_pose.y != s.map_pose.y ||
        before->map_pose.yaw != s.map_pose.yaw)
      moved.push_back(s);
  }
  const std::string history = poseHistoryPath();
  struct stat st;
  std::string text = ::stat(history.c_str(), &st) == 0 ? readFile(history) : std::string();
  if (text.empty()) text = std::string(kHistoryHeader) + "\n";
  if (text.back() != '\n') text += '\n';
  writeFileAtomic(history, text + old_lines.str());
  writeJournal(moved);
  std::swap(scans_, updated);
  try {
    writePoses();
  } catch (...) {
    std::swap(scans_, updated);
    throw;
  }
  pose_revision_ = revision;
  return revision;
}

PointCloud MapDirectory::loadScan(size_t i) const {
  if (i >= scans_.size())
    throw IoError(dir_, "no scan " + std::to_string(i) + " in a map of " + std::to_string(scans_.size()));
  return readCloud(dir_ + "/" + scans_[i].file);
}

PointCloud MapDirectory::loadScanInMap(size_t i) const {
  return transformCloud(loadScan(i), scans_.at(i).map_pose.toIsometry3f());
}

void MapDirectory::writePoses() const {
  std::vector<MapScanInfo> all = scans_;
  all.insert(all.end(), skipped_.begin(), skipped_.end());
  std::sort(all.begin(), all.end(), [](const MapScanInfo& a, const MapScanInfo& b) { return a.index < b.index; });
  std::string out = std::string(kHeader) + "\n";
  for (const MapScanInfo& s : all) out += formatLine(s) + "\n";
  writeFileAtomic(posesPath(), out);
}

PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3f& T_target_source) {
  PointCloud out = cloud;
  for (auto& p : out.points) p = T_target_source * p;
  for (auto& n : out.normals) n = T_target_source.linear() * n;
  return out;
}

}  // namespace scanstop
