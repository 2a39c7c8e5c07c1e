#pragma once
// A synthetic scanned room for tests: a closed box room with one box standing on the floor, seen
// by a rotating-scanner-like pattern of rays (vertical planes turned about z).

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "scanstop_common/map_dir.h"
#include "scanstop_common/pose.h"

namespace scanstop {
namespace test {

struct Box {
  Eigen::Vector3f lo, hi;
};

/// The room [-2.5, 2.5] x [-2, 2] x [0, 2.5] m and a box [0.8, 1.4] x [-0.5, 0.3] x [0, 0.8] m in it.
inline Box roomBounds() { return {{-2.5f, -2.0f, 0.0f}, {2.5f, 2.0f, 2.5f}}; }
inline Box roomObstacle() { return {{0.8f, -0.5f, 0.0f}, {1.4f, 0.3f, 0.8f}}; }

/// Distance along the unit ray (o, d) to the first surface of the room or the obstacle.
inline float castRoom(const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  const Box room = roomBounds(), ob = roomObstacle();
  float t = std::numeric_limits<float>::infinity();
  for (int a = 0; a < 3; ++a) {  // leaving the room
    if (d[a] > 1e-9f) t = std::min(t, (room.hi[a] - o[a]) / d[a]);
    if (d[a] < -1e-9f) t = std::min(t, (room.lo[a] - o[a]) / d[a]);
  }
  float t0 = 0.0f, t1 = std::numeric_limits<float>::infinity();  // slab test of the obstacle
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-9f) {
      if (o[a] < ob.lo[a] || o[a] > ob.hi[a]) return t;
      continue;
    }
    float ta = (ob.lo[a] - o[a]) / d[a], tb = (ob.hi[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 <= t1 && t0 > 0.0f) t = std::min(t, t0);
  return t;
}

/// Scan points (map frame) from the scanner at origin: planes vertical planes, beams per plane,
/// Gaussian range noise sigma_m; rays more than 60 deg below the horizon are blocked by the robot.
inline std::vector<Eigen::Vector3f> scanRoom(const Eigen::Vector3f& origin, int planes, int beams, float sigma_m = 0.0f,
                                             unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, sigma_m);
  std::vector<Eigen::Vector3f> out;
  for (int k = 0; k < planes; ++k) {
    const float phi = static_cast<float>(M_PI) * k / planes;
    for (int b = 0; b < beams; ++b) {
      const float theta = -static_cast<float>(M_PI) + 2.0f * static_cast<float>(M_PI) * (b + 0.5f) / beams;
      const Eigen::Vector3f d(std::cos(theta) * std::cos(phi), std::cos(theta) * std::sin(phi), std::sin(theta));
      if (d.z() < -std::sin(static_cast<float>(M_PI) / 3.0f)) continue;
      const float t = castRoom(origin, d);
      if (!std::isfinite(t)) continue;
      out.push_back(origin + (t + (sigma_m > 0 ? noise(rng) : 0.0f)) * d);
    }
  }
  return out;
}

/// A map directory with two scans of the room (400 planes, 1000 beams, 5 mm noise), robot poses
/// (0, 0, 0) and (-1, 0.5, 90 deg), the scanner 0.45 m above base_link.
inline void writeRoomMap(const std::string& dir) {
  MapDirectory map(dir);
  const Pose2D poses[2] = {Pose2D(0.0, 0.0, 0.0), Pose2D(-1.0, 0.5, M_PI / 2)};
  for (uint32_t i = 0; i < 2; ++i) {
    MapScanInfo info;
    info.index = i;
    info.map_pose = poses[i];
    info.sensor_origin = Eigen::Vector3d(0.0, 0.0, 0.45);
    const Eigen::Isometry3f T_map_base = poses[i].toIsometry3f();
    const Eigen::Vector3f origin = T_map_base * info.sensor_origin.cast<float>();
    PointCloud base;
    for (const auto& p : scanRoom(origin, 400, 1000, 0.005f, i + 1)) base.push_back(T_map_base.inverse() * p);
    map.append(info, base);
  }
}

}  // namespace test
}  // namespace scanstop
