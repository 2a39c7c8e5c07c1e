#pragma once
// Synthetic test worlds with known answers: free floor as a mask on a 0.05 m grid, the floor
// grid an ideal extraction would give, and simulated scans (floor + wall points) of it.
#include <Eigen/Core>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "scanstop_explorer/floor_map.h"
#include "scanstop_explorer/grid.h"
#include "scanstop_explorer/planner.h"

namespace scanstop {
namespace explorer {
namespace test {

struct Scene {
  GridGeometry geometry;  // origin (-1, -1), 0.05 m
  cv::Mat free;           // CV_8U 1 = free floor in the world
};

inline Scene emptyScene(double w_m, double h_m) {
  Scene s;
  s.geometry.origin_x = -1.0;
  s.geometry.origin_y = -1.0;
  s.geometry.resolution = 0.05;
  s.geometry.width = static_cast<int>(std::lround((w_m + 2.0) / 0.05));
  s.geometry.height = static_cast<int>(std::lround((h_m + 2.0) / 0.05));
  s.free = cv::Mat::zeros(s.geometry.height, s.geometry.width, CV_8U);
  return s;
}

/// Sets the cells whose centres lie in the map box [x0, x1] x [y0, y1] to v.
inline void box(Scene& s, double x0, double y0, double x1, double y1, uint8_t v) {
  for (int r = 0; r < s.free.rows; ++r)
    for (int c = 0; c < s.free.cols; ++c) {
      const Eigen::Vector2d p = s.geometry.center({c, r});
      if (p.x() >= x0 && p.x() <= x1 && p.y() >= y0 && p.y() <= y1) s.free.at<uint8_t>(r, c) = v;
    }
}

inline void disc(Scene& s, double x, double y, double radius, uint8_t v) {
  for (int r = 0; r < s.free.rows; ++r)
    for (int c = 0; c < s.free.cols; ++c)
      if ((s.geometry.center({c, r}) - Eigen::Vector2d(x, y)).norm() <= radius) s.free.at<uint8_t>(r, c) = v;
}

/// 6 x 1.2 m corridor from (0, 0).
inline Scene corridor() {
  Scene s = emptyScene(6.0, 1.2);
  box(s, 0, 0, 6.0, 1.2, 1);
  return s;
}
/// Two 4 x 4 m rooms side by side, joined by a 1 m door in the middle of the shared wall.
inline Scene twoRooms() {
  Scene s = emptyScene(8.2, 4.0);
  box(s, 0, 0, 4.0, 4.0, 1);
  box(s, 4.2, 0, 8.2, 4.0, 1);
  box(s, 3.9, 1.5, 4.3, 2.5, 1);
  return s;
}
/// L shape: a 5 x 1.5 m arm along x and a 1.5 x 5 m arm along y.
inline Scene lShape() {
  Scene s = emptyScene(5.0, 5.0);
  box(s, 0, 0, 5.0, 1.5, 1);
  box(s, 0, 0, 1.5, 5.0, 1);
  return s;
}
/// A ring: outer radius 3 m, inner radius 1.8 m, centred at (3, 3).
inline Scene donut() {
  Scene s = emptyScene(6.0, 6.0);
  disc(s, 3.0, 3.0, 3.0, 1);
  disc(s, 3.0, 3.0, 1.8, 0);
  return s;
}
/// A 5 x 5 m room with a table whose four 10 cm legs stand 1.6 x 1.0 m apart around (2.5, 2.5).
inline Scene tableRoom() {
  Scene s = emptyScene(5.0, 5.0);
  box(s, 0, 0, 5.0, 5.0, 1);
  for (double dx : {-0.8, 0.8})
    for (double dy : {-0.5, 0.5}) box(s, 2.5 + dx - 0.03, 2.5 + dy - 0.03, 2.5 + dx + 0.03, 2.5 + dy + 0.03, 0);
  return s;
}

/// The ideal floor grid: free cells floor, non-free cells next to free ones obstacle, rest unknown.
inline cv::Mat idealStates(const Scene& s) {
  cv::Mat grown;
  cv::dilate(s.free, grown, cv::Mat::ones(3, 3, CV_8U));
  cv::Mat states = cv::Mat::zeros(s.free.size(), CV_8U);
  states.setTo(kObstacle, grown & (s.free == 0));
  states.setTo(kFloor, s.free);
  return states;
}

/// Free cells a scanner at p sees within range_m (line of sight through free cells).
inline cv::Mat visibleFree(const Scene& s, const Eigen::Vector2d& p, double range_m) {
  cv::Mat vis = cv::Mat::zeros(s.free.size(), CV_8U);
  const Eigen::Vector2d pg = s.geometry.toGrid(p);
  for (int r = 0; r < s.free.rows; ++r)
    for (int c = 0; c < s.free.cols; ++c) {
      if (!s.free.at<uint8_t>(r, c)) continue;
      if ((s.geometry.center({c, r}) - p).norm() > range_m) continue;
      if (segmentClear(s.free, pg, Eigen::Vector2d(c + 0.5, r + 0.5))) vis.at<uint8_t>(r, c) = 1;
    }
  return vis;
}

/// A simulated scan from p in the map frame: a floor point (z = 0) on every visible free cell and
/// wall points (z = 0.2, 0.4 and 1.5 m) on every obstacle cell next to a visible free cell.
inline std::vector<Eigen::Vector3f> simulateScan(const Scene& s, const Eigen::Vector2d& p, double range_m) {
  const cv::Mat vis = visibleFree(s, p, range_m);
  cv::Mat near;
  cv::dilate(vis, near, cv::Mat::ones(3, 3, CV_8U));
  std::vector<Eigen::Vector3f> pts;
  for (int r = 0; r < s.free.rows; ++r)
    for (int c = 0; c < s.free.cols; ++c) {
      const Eigen::Vector2d q = s.geometry.center({c, r});
      if (vis.at<uint8_t>(r, c))
        pts.emplace_back(q.x(), q.y(), 0.0f);
      else if (near.at<uint8_t>(r, c) && !s.free.at<uint8_t>(r, c)) {
        pts.emplace_back(q.x(), q.y(), 0.2f);
        pts.emplace_back(q.x(), q.y(), 0.4f);
        pts.emplace_back(q.x(), q.y(), 1.5f);
      }
    }
  return pts;
}

/// Ideal scene states restricted to what scans from `positions` saw.
inline cv::Mat seenStates(const Scene& s, const std::vector<Eigen::Vector2d>& positions, double range_m) {
  cv::Mat vis = cv::Mat::zeros(s.free.size(), CV_8U);
  for (const auto& p : positions) vis |= visibleFree(s, p, range_m);
  cv::Mat near;
  cv::dilate(vis, near, cv::Mat::ones(3, 3, CV_8U));
  cv::Mat states = cv::Mat::zeros(s.free.size(), CV_8U);
  states.setTo(kObstacle, near & (s.free == 0));
  states.setTo(kFloor, vis);
  return states;
}

/// Checks a polyline densely (every 1/20 cell) against the accessible mask.
inline bool polylineOnAccessible(const GridGeometry& g, const cv::Mat& accessible,
                                 const std::vector<Eigen::Vector2d>& path, size_t first_segment = 0) {
  for (size_t i = first_segment + 1; i < path.size(); ++i) {
    const Eigen::Vector2d a = g.toGrid(path[i - 1]), b = g.toGrid(path[i]);
    const int n = static_cast<int>(std::ceil((b - a).norm() * 20)) + 1;
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector2d q = a + (b - a) * (static_cast<double>(k) / n);
      const cv::Point c(static_cast<int>(std::floor(q.x())), static_cast<int>(std::floor(q.y())));
      if (!g.contains(c) || !accessible.at<uint8_t>(c)) return false;
    }
  }
  return true;
}

}  // namespace test
}  // namespace explorer
}  // namespace scanstop
