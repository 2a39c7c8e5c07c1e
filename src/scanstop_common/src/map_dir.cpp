#include "scanstop_common/map_dir.h"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/file_util.h"

namespace scanstop {
namespace {

const char* const kHeader =
    "index,file,stamp_s,map_x,map_y,map_yaw,odom_x,odom_y,odom_yaw,sensor_x,sensor_y,sensor_z,"
    "converged,iterations,correspondences,rms_m,overlap";
constexpr size_t kColumns = 17;

/// Creates the directory and any missing parents (like mkdir -p).
void makeDirectory(const std::string& path) {
  for (size_t pos = path.find('/', 1); pos != std::string::npos; pos = path.find('/', pos + 1)) {
    const std::string parent = path.substr(0, pos);
    if (::mkdir(parent.c_str(), 0755) != 0 && errno != EEXIST)
      throw IoError(parent, std::string("cannot create directory: ") + std::strerror(errno));
  }
  if (::mkdir(path.c_str(), 0755) != 0 && errno != EEXIST)
    throw IoError(path, std::string("cannot create directory: ") + std::strerror(errno));
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) throw IoError(path, "exists but is not a directory");
}

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(item);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

MapScanInfo parseLine(const std::string& line, const std::string& path, size_t line_no) {
  const std::vector<std::string> f = splitCsv(line);
  const auto fail = [&](const std::string& what) {
    throw IoError(path, "line " + std::to_string(line_no) + ": " + what);
  };
  if (f.size() != kColumns)
    fail("expected " + std::to_string(kColumns) + " comma-separated values, found " + std::to_string(f.size()));
  std::vector<double> v(kColumns, 0.0);
  for (size_t i = 0; i < kColumns; ++i) {
    if (i == 1) continue;
    char* end = nullptr;
    v[i] = std::strtod(f[i].c_str(), &end);
    if (f[i].empty() || *end != '\0' || !std::isfinite(v[i])) fail("column " + std::to_string(i + 1) + " ('" + f[i] + "') is not a finite number");
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
  if (info.file.empty() || info.file.find("..") != std::string::npos || info.file[0] == '/')
    fail("scan file name '" + info.file + "' must be a relative path inside the map directory");
  return info;
}

std::string formatLine(const MapScanInfo& s) {
  std::ostringstream out;
  out << std::setprecision(17) << s.index << ',' << s.file << ',' << s.stamp_s << ',' << s.map_pose.x << ','
      << s.map_pose.y << ',' << s.map_pose.yaw << ',' << s.odom_pose.x << ',' << s.odom_pose.y << ','
      << s.odom_pose.yaw << ',' << s.sensor_origin.x() << ',' << s.sensor_origin.y() << ',' << s.sensor_origin.z()
      << ',' << (s.converged ? 1 : 0) << ',' << s.iterations << ',' << s.correspondences << ',' << s.rms_m << ','
      << s.overlap;
  return out.str();
}

}  // namespace

MapDirectory::MapDirectory(const std::string& dir) : dir_(dir) {
  while (dir_.size() > 1 && dir_.back() == '/') dir_.pop_back();
  if (dir_.empty()) throw IoError(dir, "empty map directory name");
  makeDirectory(dir_);
  makeDirectory(dir_ + "/scans");
  std::ifstream in(posesPath());
  if (!in) return;  // a new map
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 1) {
      if (line != kHeader) throw IoError(posesPath(), "line 1: not a scanstop poses header");
      continue;
    }
    if (line.empty()) continue;
    MapScanInfo info = parseLine(line, posesPath(), line_no);
    if (info.index != scans_.size())
      throw IoError(posesPath(), "line " + std::to_string(line_no) + ": scan index " + std::to_string(info.index) +
                                     " where " + std::to_string(scans_.size()) + " was expected");
    scans_.push_back(info);
  }
}

void MapDirectory::append(MapScanInfo info, const PointCloud& cloud_base) {
  if (info.index != scans_.size())
    throw IoError(posesPath(), "cannot append scan " + std::to_string(info.index) + ": the map has " +
                                   std::to_string(scans_.size()) + " scans");
  char name[32];
  std::snprintf(name, sizeof(name), "scans/scan_%04u.pcd", info.index);
  info.file = name;
  writeCloud(dir_ + "/" + info.file, removeNonFinite(cloud_base));
  scans_.push_back(info);
  try {
    writePoses();
  } catch (...) {
    scans_.pop_back();
    throw;
  }
}

void MapDirectory::updateInfo(const MapScanInfo& info) {
  if (info.index >= scans_.size())
    throw IoError(posesPath(), "cannot update scan " + std::to_string(info.index) + ": no such scan");
  const MapScanInfo old = scans_[info.index];
  scans_[info.index] = info;
  scans_[info.index].file = old.file;
  try {
    writePoses();
  } catch (...) {
    scans_[info.index] = old;
    throw;
  }
}

PointCloud MapDirectory::loadScan(size_t i) const {
  if (i >= scans_.size()) throw IoError(dir_, "no scan " + std::to_string(i) + " in a map of " + std::to_string(scans_.size()));
  return readCloud(dir_ + "/" + scans_[i].file);
}

PointCloud MapDirectory::loadScanInMap(size_t i) const {
  return transformCloud(loadScan(i), scans_.at(i).map_pose.toIsometry3f());
}

void MapDirectory::writePoses() const {
  std::string out = std::string(kHeader) + "\n";
  for (const MapScanInfo& s : scans_) out += formatLine(s) + "\n";
  writeFileAtomic(posesPath(), out);
}

PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3f& T_target_source) {
  PointCloud out = cloud;
  for (auto& p : out.points) p = T_target_source * p;
  for (auto& n : out.normals) n = T_target_source.linear() * n;
  return out;
}

}  // namespace scanstop
