#include "scanstop_eval/ground_truth.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "scanstop_explorer/explorer.h"
#include "scanstop_explorer/floor_map.h"
#include "scanstop_explorer/parameters.h"

namespace scanstop {
namespace eval {

using explorer::Explorer;
using explorer::kFloor;

ReachableFloor reachableFloor(const TriangleMesh& world, const Pose2D& start_world, double robot_radius_m,
                              double resolution, double z_lo, double z_hi) {
  if (world.faces.empty()) throw std::invalid_argument("the true reachable floor: the world mesh has no triangles");
  if (!(resolution > 0.0) || !(robot_radius_m > 0.0) || !(z_hi > z_lo))
    throw std::invalid_argument("the true reachable floor: resolution and robot radius must be positive, z_hi > z_lo");
  ReachableFloor out;
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const Eigen::Vector3f& v : world.vertices) {
    lo = lo.cwiseMin(v.head<2>().cast<double>());
    hi = hi.cwiseMax(v.head<2>().cast<double>());
  }
  GridGeometry& g = out.geometry;
  g.resolution = resolution;
  g.origin_x = std::floor(lo.x() / resolution) * resolution - resolution;
  g.origin_y = std::floor(lo.y() / resolution) * resolution - resolution;
  // Sizes in double before any cast (a vertex at 1e30 m overflowed int), capped at kMaxGridCells:
  // about 13 bytes per cell in the masks below, so at most ~260 MB (issue #22 class 3).
  constexpr double kMaxGridCells = 2e7;
  const double w = std::ceil((hi.x() - g.origin_x) / resolution) + 2,
               h = std::ceil((hi.y() - g.origin_y) / resolution) + 2;
  if (!(w > 0 && h > 0 && w * h <= kMaxGridCells)) {
    std::ostringstream what;
    what << "the true reachable floor: the world's extent x [" << lo.x() << ", " << hi.x() << "] y [" << lo.y() << ", "
         << hi.y() << "] m needs a grid of " << w << " x " << h << " cells at " << resolution
         << " m, more than the limit of " << kMaxGridCells << " cells";
    throw std::invalid_argument(what.str());
  }
  g.width = static_cast<int>(w);
  g.height = static_cast<int>(h);
  out.obstacle = cv::Mat::zeros(g.height, g.width, CV_8U);
  auto px = [&](const Eigen::Vector3f& v) {
    return cv::Point(static_cast<int>(std::floor((v.x() - g.origin_x) / resolution)),
                     static_cast<int>(std::floor((v.y() - g.origin_y) / resolution)));
  };
  cv::Mat floor = cv::Mat::zeros(g.height, g.width, CV_8U);  // cells under a floor triangle
  for (const Eigen::Vector3i& f : world.faces) {
    const Eigen::Vector3f& a = world.vertices.at(f[0]);
    const Eigen::Vector3f& b = world.vertices.at(f[1]);
    const Eigen::Vector3f& c = world.vertices.at(f[2]);
    const float zmin = std::min({a.z(), b.z(), c.z()}), zmax = std::max({a.z(), b.z(), c.z()});
    const cv::Point pts[3] = {px(a), px(b), px(c)};
    if (zmax < z_lo) {  // floor
      cv::fillConvexPoly(floor, pts, 3, cv::Scalar(1));
      continue;
    }
    if (zmin > z_hi) continue;  // ceiling, table tops above the layer
    cv::fillConvexPoly(out.obstacle, pts, 3, cv::Scalar(1));
    cv::polylines(out.obstacle, std::vector<cv::Point>(pts, pts + 3), true, cv::Scalar(1));  // vertical faces
  }
  // The robot stands on the floor: where the world has floor triangles, a cell without one (beyond
  // the floor's edge) is no place for the disc either (a world without any: everywhere is floor).
  out.blocked = out.obstacle.clone();
  if (cv::countNonZero(floor) > 0) out.blocked |= (floor == 0) / 255;
  const cv::Point s = g.cellOf(start_world.x, start_world.y);
  if (!g.contains(s) || out.blocked.at<uint8_t>(s))
    throw std::invalid_argument("the true reachable floor: the start (" + std::to_string(start_world.x) + ", " +
                                std::to_string(start_world.y) +
                                ") is outside the world, off its floor or inside an obstacle");
  // Free cells whose distance to an obstacle is at least the radius, component of the start.
  cv::Mat dist;
  cv::distanceTransform(1 - out.blocked, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat centres = dist >= static_cast<float>(robot_radius_m / resolution);
  if (!centres.at<uint8_t>(s))
    throw std::invalid_argument("the true reachable floor: the robot disc does not fit at the start");
  cv::Mat mask = cv::Mat::zeros(g.height + 2, g.width + 2, CV_8U);
  cv::floodFill(centres, mask, s, cv::Scalar(255), nullptr, cv::Scalar(), cv::Scalar(),
                4 | cv::FLOODFILL_MASK_ONLY | (1 << 8));
  out.centres = mask(cv::Rect(1, 1, g.width, g.height)).clone();
  // Swept floor: the component grown by the robot radius, obstacles excluded.
  const int r = static_cast<int>(std::ceil(robot_radius_m / resolution));
  cv::Mat swept;
  cv::dilate(out.centres, swept, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
  out.reachable = (swept != 0) & (out.blocked == 0);
  out.reachable /= 255;
  out.reachable_m2 = cv::countNonZero(out.reachable) * g.cellArea();
  return out;
}

GroundTruthCoverage groundTruthCoverage(const TriangleMesh& world, const Pose2D& start_world, const cv::Mat& states,
                                        const GridGeometry& mg, const Pose2D& T_world_map, double robot_radius_m,
                                        double resolution, double z_lo, double z_hi, double tolerance_m) {
  if (world.faces.empty()) throw std::invalid_argument("groundTruthCoverage: the world mesh has no triangles");
  if (!(resolution > 0.0) || !(robot_radius_m > 0.0) || !(z_hi > z_lo) || !(tolerance_m >= 0.0))
    throw std::invalid_argument(
        "groundTruthCoverage: resolution, robot radius and tolerance must be positive, z_hi > z_lo");
  if (states.type() != CV_8U || states.cols != mg.width || states.rows != mg.height)
    throw std::invalid_argument("groundTruthCoverage: states must be CV_8U of the map geometry's size");
  ReachableFloor truth = reachableFloor(world, start_world, robot_radius_m, resolution, z_lo, z_hi);
  GroundTruthCoverage out;
  out.robot_radius_m = robot_radius_m;
  out.geometry = truth.geometry;
  out.obstacle = truth.obstacle;
  out.reachable = truth.reachable;
  const GridGeometry& g = out.geometry;
  // Map floor in the world grid, grown by the tolerance.
  cv::Mat map_floor = cv::Mat::zeros(g.height, g.width, CV_8U);
  for (int row = 0; row < mg.height; ++row)
    for (int col = 0; col < mg.width; ++col) {
      if (states.at<uint8_t>(row, col) != kFloor) continue;
      const Eigen::Vector2d m = mg.center({col, row});
      const Pose2D w = T_world_map * Pose2D(m.x(), m.y(), 0.0);
      const cv::Point c = g.cellOf(w.x, w.y);
      if (g.contains(c)) map_floor.at<uint8_t>(c) = 1;
    }
  const int t = static_cast<int>(std::ceil(tolerance_m / resolution));
  if (t > 0)
    cv::dilate(map_floor, map_floor, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * t + 1, 2 * t + 1)));
  out.observed = out.reachable & map_floor;
  const int n_reach = cv::countNonZero(out.reachable), n_obs = cv::countNonZero(out.observed);
  out.reachable_m2 = n_reach * g.cellArea();
  out.observed_m2 = n_obs * g.cellArea();
  out.coverage = n_reach > 0 ? static_cast<double>(n_obs) / n_reach : 0.0;
  return out;
}

GroundTruthCoverage groundTruthCoverageOfMap(const TriangleMesh& world, const Pose2D& start_world,
                                             const MapDirectory& map, double robot_radius_m, double tolerance_m,
                                             std::vector<std::string>* problems, const ExplorerConfig& config) {
  if (map.size() == 0) throw std::invalid_argument("map directory " + map.dir() + " holds no scans");
  Explorer ex(config);
  ex.loadMapDirectory(map, problems);
  GroundTruthCoverage c = groundTruthCoverage(world, start_world, ex.floorMap().states(), ex.floorMap().geometry(),
                                              start_world, robot_radius_m, 0.05, 0.03, 0.63, tolerance_m);
  c.scans = ex.scanCount();
  return c;
}

GroundTruthCoverage groundTruthCoverageOfRun(const TriangleMesh& world, const Pose2D& start_world,
                                             const MapDirectory& map, const std::string& explorer_config_file,
                                             std::optional<double> robot_radius_m, std::string* note) {
  ExplorerConfig config;
  if (note) note->clear();
  struct stat st;
  if (!explorer_config_file.empty() && ::stat(explorer_config_file.c_str(), &st) == 0)
    explorer::readParameterFile(explorer_config_file, config);
  else if (note)
    *note = "no explorer configuration " +
            (explorer_config_file.empty() ? std::string("given") : explorer_config_file) + ": the explorer's defaults";
  return groundTruthCoverageOfMap(world, start_world, map, robot_radius_m.value_or(config.planner.robot_radius_m), 0.1,
                                  nullptr, config);
}

}  // namespace eval
}  // namespace scanstop
