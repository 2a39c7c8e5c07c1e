#include "scanstop_mesher/fused_tracker.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/config.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/mesher.h"

namespace scanstop {
namespace mesher {

void FusedTrackerConfig::validate() const {
  requireInRange("repose_m", repose_m, 0.0, 1.0, "m");
  requireInRange("repose_deg", repose_deg, 0.0, 180.0, "deg");
}

FusedMapTracker::FusedMapTracker(const FusedMapConfig& map_config, const FusedTrackerConfig& config)
    : config_(config), map_(map_config) {
  config_.validate();
}

namespace {

/// A scan's readings in the map frame at `pose`, and its sensor origin there.
void inMap(const PointCloud& scan, const Pose2D& pose, const Eigen::Vector3d& sensor_origin,
           std::vector<Eigen::Vector3f>* points, Eigen::Vector3f* origin) {
  const Eigen::Isometry3f T = pose.toIsometry3f();
  points->resize(scan.points.size());
  for (size_t i = 0; i < scan.points.size(); ++i) (*points)[i] = T * scan.points[i];  // NaN stays NaN
  *origin = T * sensor_origin.cast<float>();
}

}  // namespace

FusedTrackerUpdate FusedMapTracker::update(const std::string& dir) {
  const auto t0 = std::chrono::steady_clock::now();
  FusedTrackerUpdate out;
  dir_ = dir;
  const std::unique_ptr<const MapDirectory> map = openMapDirectory(dir, &out.problems);
  const double turn = config_.repose_deg * M_PI / 180.0;
  std::vector<Eigen::Vector3f> points;
  Eigen::Vector3f origin;
  std::vector<size_t> fresh;  // positions in map->scans() of the scans not integrated yet
  for (size_t s = 0; s < map->size(); ++s) {
    const MapScanInfo& info = map->scans()[s];
    const auto known = tracked_.find(info.index);
    if (known == tracked_.end()) {
      fresh.push_back(s);  // new: integrated below, on threads when there are several
      continue;
    }
    {
      const Tracked& was = known->second;
      const double moved = std::hypot(info.map_pose.x - was.pose.x, info.map_pose.y - was.pose.y);
      const double turned = std::abs(std::remainder(info.map_pose.yaw - was.pose.yaw, 2.0 * M_PI));
      if (moved <= config_.repose_m && turned <= turn && info.sensor_origin == was.sensor_origin &&
          info.file == was.file)
        continue;
    }
    PointCloud scan;
    try {
      scan = map->loadScan(s);
    } catch (const std::exception& e) {
      out.problems.push_back("scan " + std::to_string(info.index) + " skipped: " + e.what());
      continue;
    }
    {  // moved: taken back where it was integrated (the same file's points)
      const Tracked& was = known->second;
      PointCloud old_scan = scan;
      if (was.file != info.file) {
        try {
          old_scan = readCloud(dir + "/" + was.file);
        } catch (const std::exception& e) {
          out.problems.push_back("scan " + std::to_string(info.index) +
                                 ": its earlier file cannot be read to take it "
                                 "back (" +
                                 e.what() + "): kept at its earlier pose");
          continue;
        }
      }
      inMap(old_scan, was.pose, was.sensor_origin, &points, &origin);
      map_.deintegrate(points, origin);
      ++out.reintegrated;
    }
    inMap(scan, info.map_pose, info.sensor_origin, &points, &origin);
    map_.integrate(points, origin);
    tracked_[info.index] = Tracked{info.map_pose, info.sensor_origin, info.file};
  }
  // The new scans: runs of them on map_config.threads threads (a map started on a long directory, a
  // node restarted late in a mission), each into grids of its own, merged.
  const int threads =
      static_cast<int>(std::min<size_t>(std::max(1, map_.config().threads), std::max<size_t>(fresh.size(), 1)));
  std::vector<std::unique_ptr<FusedMap>> parts;
  FusedMapConfig part_config = map_.config();
  part_config.max_grid_mb = std::max(1.0, map_.config().max_grid_mb / std::max(1, threads));  // validate()'s least
  for (int t = 0; t < threads; ++t) parts.emplace_back(new FusedMap(part_config));
  std::vector<std::vector<std::string>> problems(std::max(1, threads));
  std::vector<std::vector<char>> done(std::max(1, threads));
  const auto first = [&](int t) { return fresh.size() * static_cast<size_t>(t) / static_cast<size_t>(threads); };
  if (!fresh.empty())
    runInThreads(threads, [&](int t) {
      std::vector<Eigen::Vector3f> pts;
      Eigen::Vector3f org;
      for (size_t k = first(t); k < first(t + 1); ++k) {
        const MapScanInfo& info = map->scans()[fresh[k]];
        PointCloud scan;
        try {
          scan = map->loadScan(fresh[k]);
        } catch (const std::exception& e) {
          problems[t].push_back("scan " + std::to_string(info.index) + " skipped: " + e.what());
          done[t].push_back(0);
          continue;
        }
        inMap(scan, info.map_pose, info.sensor_origin, &pts, &org);
        parts[t]->integrate(pts, org);
        done[t].push_back(1);
      }
    });
  for (int t = 0; t < threads && !fresh.empty(); ++t) {
    map_.merge(*parts[t]);
    parts[t].reset();
    out.problems.insert(out.problems.end(), problems[t].begin(), problems[t].end());
    for (size_t k = first(t), j = 0; k < first(t + 1); ++k, ++j) {
      if (!done[t][j]) continue;
      const MapScanInfo& info = map->scans()[fresh[k]];
      tracked_[info.index] = Tracked{info.map_pose, info.sensor_origin, info.file};
      ++out.integrated;
    }
  }
  out.scans = tracked_.size();
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

FusedMap FusedMapTracker::snapshot() const {
  FusedMap copy = map_.copy();
  if (!map_.config().carve_far || tracked_.empty()) return copy;
  std::vector<const Tracked*> scans;
  for (const auto& entry : tracked_) scans.push_back(&entry.second);
  copy.carveFarAll(
      scans.size(),
      [&](size_t s, std::vector<Eigen::Vector3f>& points, Eigen::Vector3f& origin) {
        PointCloud scan;
        try {
          scan = readCloud(dir_ + "/" + scans[s]->file);
        } catch (const std::exception&) {
          return false;  // integrated, then gone: its near part stays, its far part is left out
        }
        inMap(scan, scans[s]->pose, scans[s]->sensor_origin, &points, &origin);
        return true;
      },
      map_.config().threads);
  return copy;
}

}  // namespace mesher
}  // namespace scanstop
