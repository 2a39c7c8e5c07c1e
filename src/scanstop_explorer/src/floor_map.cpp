#include "scanstop_explorer/floor_map.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "scanstop_common/config.h"

namespace scanstop {
namespace explorer {
namespace {
/// Largest floor grid [cells]: 10 million (250 m x 200 m at 5 cm); the grid and the planner's
/// images of it take well under 1 GB at this size.
constexpr double kMaxGridCells = 1e7;
}  // namespace

cv::Point GridGeometry::cellOf(double x_m, double y_m) const {
  return {static_cast<int>(std::floor((x_m - origin_x) / resolution)),
          static_cast<int>(std::floor((y_m - origin_y) / resolution))};
}

void FloorConfig::validate() const {
  requireInRange("resolution_m", resolution_m, 0.005, 1.0, "m");
  requireInRange("floor_layer_m", floor_layer_m, 1e-6, 0.5, "m");
  requireInRange("robot_height_m", robot_height_m, 1e-6, 5.0, "m");
  requireInRange("grid_margin_m", grid_margin_m, 0.0, 20.0, "m");
  requireInRange("min_floor_points", min_floor_points, 1, 1000);
  requireInRange("min_obstacle_points", min_obstacle_points, 1, 1000);
  requireInRange("speckle_min_points", speckle_min_points, 1, 1000);
  requireInRange("speckle_max_cells", speckle_max_cells, 1, 100);
  requireInRange("min_obstacle_scans", min_obstacle_scans, 0, 1000);
  requireInRange("max_extent_m", max_extent_m, 1e-3, 1e4, "m");
  requireInRange("floor_fill_radius_m", floor_fill_radius_m, 0.0, 1.0, "m");
}

FloorMap::FloorMap(const FloorConfig& config) : config_(config) {
  config_.validate();
  geometry_.resolution = config_.resolution_m;
}

void FloorMap::ensureContains(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  const double res = config_.resolution_m;
  if (!empty()) {
    const double x1 = geometry_.origin_x + geometry_.width * res, y1 = geometry_.origin_y + geometry_.height * res;
    if (lo.x() >= geometry_.origin_x && lo.y() >= geometry_.origin_y && hi.x() < x1 && hi.y() < y1) return;
  }
  // New bounds on the global lattice (multiples of the resolution), so cells never shift.
  Eigen::Vector2d new_lo = lo.array() - config_.grid_margin_m;
  Eigen::Vector2d new_hi = hi.array() + config_.grid_margin_m;
  if (!empty()) {
    new_lo = new_lo.cwiseMin(Eigen::Vector2d(geometry_.origin_x, geometry_.origin_y));
    new_hi = new_hi.cwiseMax(
        Eigen::Vector2d(geometry_.origin_x + geometry_.width * res, geometry_.origin_y + geometry_.height * res));
  }
  // The size in double before any cast (a far-away pose overflowed long/int), capped at kMaxGridCells:
  // one far pose grew the grid (and the planner's images of it) to gigabytes (issue #22 class 3).
  const double fx0 = std::floor(new_lo.x() / res), fy0 = std::floor(new_lo.y() / res);
  const double fw = std::ceil(new_hi.x() / res) + 1 - fx0, fh = std::ceil(new_hi.y() / res) + 1 - fy0;
  if (!new_lo.allFinite() || !new_hi.allFinite() || !(fw * fh <= kMaxGridCells)) {
    char what[400];
    std::snprintf(what, sizeof what,
                  "the floor grid would span x [%.6g, %.6g] y [%.6g, %.6g] m: %.6g x %.6g cells at %g m, more than the "
                  "limit of %.0f cells (a pose or point far from the others?)",
                  new_lo.x(), new_hi.x(), new_lo.y(), new_hi.y(), fw, fh, res, kMaxGridCells);
    throw std::length_error(what);
  }
  const long ix0 = static_cast<long>(fx0), iy0 = static_cast<long>(fy0);
  const long ix1 = static_cast<long>(std::ceil(new_hi.x() / res)) + 1,
             iy1 = static_cast<long>(std::ceil(new_hi.y() / res)) + 1;
  GridGeometry g;
  g.resolution = res;
  g.origin_x = ix0 * res;
  g.origin_y = iy0 * res;
  g.width = static_cast<int>(ix1 - ix0);
  g.height = static_cast<int>(iy1 - iy0);
  cv::Mat floor = cv::Mat::zeros(g.height, g.width, CV_32S), obstacle = cv::Mat::zeros(g.height, g.width, CV_32S);
  cv::Mat obstacle_max = cv::Mat::zeros(g.height, g.width, CV_32S);
  cv::Mat obstacle_seen = cv::Mat::zeros(g.height, g.width, CV_32S);
  if (!empty()) {
    const int dx = static_cast<int>(std::lround((geometry_.origin_x - g.origin_x) / res));
    const int dy = static_cast<int>(std::lround((geometry_.origin_y - g.origin_y) / res));
    const cv::Rect roi(dx, dy, geometry_.width, geometry_.height);
    floor_hits_.copyTo(floor(roi));
    obstacle_hits_.copyTo(obstacle(roi));
    obstacle_max_.copyTo(obstacle_max(roi));
    obstacle_seen_.copyTo(obstacle_seen(roi));
  }
  geometry_ = g;
  floor_hits_ = floor;
  obstacle_hits_ = obstacle;
  obstacle_max_ = obstacle_max;
  obstacle_seen_ = obstacle_seen;
}

size_t FloorMap::addPoints(const std::vector<Eigen::Vector3f>& points_map) {
  const double half = 0.5 * config_.floor_layer_m;
  const double top = half + config_.robot_height_m;
  // First pass: bounds of the used points, so the grid grows once per scan.
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  std::vector<uint8_t> kind(points_map.size(), 0);  // 0 skip, 1 floor, 2 obstacle
  size_t used = 0;
  for (size_t i = 0; i < points_map.size(); ++i) {
    const Eigen::Vector3f& p = points_map[i];
    if (!p.allFinite() || std::abs(p.x()) > config_.max_extent_m || std::abs(p.y()) > config_.max_extent_m) continue;
    if (std::abs(p.z()) <= half)
      kind[i] = 1;
    else if (p.z() > half && p.z() <= top)
      kind[i] = 2;
    else
      continue;
    lo = lo.cwiseMin(p.head<2>().cast<double>());
    hi = hi.cwiseMax(p.head<2>().cast<double>());
    ++used;
  }
  if (used == 0) return 0;
  ensureContains(lo, hi);
  std::vector<std::pair<int, int>> obstacle_cells;  // (linear index, points of this scan)
  for (size_t i = 0; i < points_map.size(); ++i) {
    if (kind[i] == 0) continue;
    const cv::Point c = geometry_.cellOf(points_map[i].x(), points_map[i].y());
    if (!geometry_.contains(c)) continue;  // cannot happen after ensureContains
    if (kind[i] == 1)
      floor_hits_.at<int>(c)++;
    else
      obstacle_cells.emplace_back(c.y * geometry_.width + c.x, 1);
  }
  // Obstacle evidence counts per scan: a cell becomes an obstacle when this scan alone put
  // min_obstacle_points points into it.
  std::sort(obstacle_cells.begin(), obstacle_cells.end());
  for (size_t i = 0; i < obstacle_cells.size();) {
    size_t j = i;
    while (j < obstacle_cells.size() && obstacle_cells[j].first == obstacle_cells[i].first) ++j;
    const int row = obstacle_cells[i].first / geometry_.width, col = obstacle_cells[i].first % geometry_.width;
    const int n = static_cast<int>(j - i);
    if (n >= config_.min_obstacle_points) obstacle_hits_.at<int>(row, col)++;
    obstacle_seen_.at<int>(row, col)++;
    obstacle_max_.at<int>(row, col) = std::max(obstacle_max_.at<int>(row, col), n);
    i = j;
  }
  return used;
}

void FloorMap::addKnownFree(const Eigen::Vector2d& center_map, double radius_m) {
  if (!center_map.allFinite() || !(radius_m > 0.0)) return;
  ensureContains(center_map.array() - radius_m, center_map.array() + radius_m);
  known_free_.emplace_back(center_map, radius_m);
}

cv::Mat FloorMap::states() const {
  cv::Mat s = cv::Mat::zeros(geometry_.height, geometry_.width, CV_8U);
  if (empty()) return s;
  cv::Mat obstacle = obstacle_hits_ > 0;
  // Sparse evidence (grazing views, undersides, thin parts far away: fewer than
  // min_obstacle_points per scan) still counts once several scans agree on the cell.
  if (config_.min_obstacle_scans > 0) obstacle |= obstacle_seen_ >= config_.min_obstacle_scans;
  if (config_.speckle_min_points > config_.min_obstacle_points)
    removeObstacleSpeckle(obstacle, obstacle_max_, config_.speckle_min_points, config_.speckle_max_cells);
  for (int r = 0; r < geometry_.height; ++r) {
    const int* f = floor_hits_.ptr<int>(r);
    const uint8_t* o = obstacle.ptr<uint8_t>(r);
    uint8_t* out = s.ptr<uint8_t>(r);
    for (int c = 0; c < geometry_.width; ++c) {
      if (o[c])
        out[c] = kObstacle;
      else if (f[c] >= config_.min_floor_points)
        out[c] = kFloor;
    }
  }
  // Known free discs: unknown cells the robot's position sees without crossing an obstacle cell.
  cv::Mat add = cv::Mat::zeros(s.size(), CV_8U);
  for (const auto& [center, radius] : known_free_) {
    const cv::Point c0 = geometry_.cellOf(center.x(), center.y());
    const int rc = static_cast<int>(std::ceil(radius / geometry_.resolution));
    for (int r = std::max(0, c0.y - rc); r <= std::min(geometry_.height - 1, c0.y + rc); ++r)
      for (int c = std::max(0, c0.x - rc); c <= std::min(geometry_.width - 1, c0.x + rc); ++c) {
        if (s.at<uint8_t>(r, c) != kUnknown || add.at<uint8_t>(r, c)) continue;
        if ((geometry_.center({c, r}) - center).norm() > radius) continue;
        bool blocked = false;
        cv::LineIterator it(s, c0, cv::Point(c, r), 4);
        for (int i = 0; i < it.count && !blocked; ++i, ++it) blocked = **it == kObstacle;
        if (!blocked) add.at<uint8_t>(r, c) = 1;
      }
  }
  s.setTo(kFloor, add);
  fillFloorGaps(s, config_.floor_fill_radius_m / config_.resolution_m);
  return s;
}

int removeObstacleSpeckle(cv::Mat& obstacle, const cv::Mat& max_points, int min_points, int max_cells) {
  if (obstacle.empty()) return 0;
  if (obstacle.type() != CV_8U || max_points.type() != CV_32S || max_points.size() != obstacle.size())
    throw std::invalid_argument("removeObstacleSpeckle: obstacle must be CV_8U and max_points CV_32S of the same size");
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(obstacle != 0, labels, stats, centroids, 8, CV_32S);
  std::vector<uint8_t> strong(n, 0);
  for (int r = 0; r < obstacle.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    const int* m = max_points.ptr<int>(r);
    for (int c = 0; c < obstacle.cols; ++c)
      if (l[c] > 0 && m[c] >= min_points) strong[l[c]] = 1;
  }
  int cleared = 0;
  for (int r = 0; r < obstacle.rows; ++r) {
    const int* l = labels.ptr<int>(r);
    uint8_t* o = obstacle.ptr<uint8_t>(r);
    for (int c = 0; c < obstacle.cols; ++c)
      if (l[c] > 0 && !strong[l[c]] && stats.at<int>(l[c], cv::CC_STAT_AREA) <= max_cells) {
        o[c] = 0;
        ++cleared;
      }
  }
  return cleared;
}

void fillFloorGaps(cv::Mat& states, double radius_cells) {
  const int r = static_cast<int>(std::floor(radius_cells));
  if (r < 1 || states.empty()) return;
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
  cv::Mat closed;
  cv::morphologyEx(states == kFloor, closed, cv::MORPH_CLOSE, kernel);
  states.setTo(kFloor, closed & (states == kUnknown));
}

}  // namespace explorer
}  // namespace scanstop
