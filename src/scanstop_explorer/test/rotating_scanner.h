#pragma once
// A minimal rotating-2D-scanner model for tests: a vertical scan fan (URG-04LX-like, 240 deg)
// turned about the vertical axis through `planes` steps over 180 deg, ray-cast against a room of
// axis-aligned boxes with a floor at z = 0. Noise-free; enough to reproduce the real sampling
// pattern (dense radial floor lines, angular gaps growing with range).
#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace scanstop {
namespace explorer {
namespace test {

struct Box {
  Eigen::Vector3d lo, hi;
};

struct BoxWorld {
  Eigen::Vector2d room_lo{0.0, 0.0}, room_hi{10.0, 8.0};  // walls enclose this rectangle
  double ceiling = 2.5;
  std::vector<Box> boxes;  // furniture

  /// Distance along the unit ray to the first surface, or +inf.
  double cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
    double best = std::numeric_limits<double>::infinity();
    auto plane = [&](double oc, double dc, double v) {
      if (std::abs(dc) < 1e-12) return;
      const double t = (v - oc) / dc;
      if (t > 1e-9 && t < best) best = t;
    };
    plane(o.z(), d.z(), 0.0);
    plane(o.z(), d.z(), ceiling);
    plane(o.x(), d.x(), room_lo.x());
    plane(o.x(), d.x(), room_hi.x());
    plane(o.y(), d.y(), room_lo.y());
    plane(o.y(), d.y(), room_hi.y());
    for (const Box& b : boxes) {  // slab test
      double t0 = 0.0, t1 = best;
      bool hit = true;
      for (int k = 0; k < 3 && hit; ++k) {
        if (std::abs(d[k]) < 1e-12) {
          hit = o[k] >= b.lo[k] && o[k] <= b.hi[k];
          continue;
        }
        double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
        if (a > c) std::swap(a, c);
        t0 = std::max(t0, a);
        t1 = std::min(t1, c);
        hit = t0 <= t1;
      }
      if (hit && t0 > 1e-9 && t0 < best) best = t0;
    }
    return best;
  }
  /// True when the disc of `radius` at (x, y) is clear of walls and of furniture below `height`.
  bool discFree(const Eigen::Vector2d& p, double radius, double height) const {
    if (p.x() - radius < room_lo.x() || p.y() - radius < room_lo.y() || p.x() + radius > room_hi.x() ||
        p.y() + radius > room_hi.y())
      return false;
    for (const Box& b : boxes) {
      if (b.lo.z() > height) continue;
      const double dx = std::max({b.lo.x() - p.x(), 0.0, p.x() - b.hi.x()});
      const double dy = std::max({b.lo.y() - p.y(), 0.0, p.y() - b.hi.y()});
      if (dx * dx + dy * dy < radius * radius) return false;
    }
    return true;
  }
};

/// A 3D scan from base_link pose (x, y) (scanner centre `height` above the floor), map frame.
/// `outlier_rate` of the beams return a random range (uniform over (0.02, max_range]) instead, as
/// the thesis' scanner model does (chapter 6.3); `seed` makes them repeatable.
inline std::vector<Eigen::Vector3f> rotatingScan(const BoxWorld& w, const Eigen::Vector2d& xy, double height = 0.45,
                                                 int planes = 100, int beams = 683, double max_range = 4.0,
                                                 double outlier_rate = 0.0, unsigned seed = 1) {
  std::vector<Eigen::Vector3f> pts;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const Eigen::Vector3d o(xy.x(), xy.y(), height);
  for (int p = 0; p < planes; ++p) {
    const double phi = M_PI * p / planes;  // plane azimuth
    const Eigen::Vector3d u(std::cos(phi), std::sin(phi), 0.0);
    for (int b = 0; b < beams; ++b) {
      const double a = -2.0 * M_PI / 3.0 + (4.0 * M_PI / 3.0) * b / (beams - 1);  // in-plane angle from +z
      const Eigen::Vector3d d = (u * std::sin(a) + Eigen::Vector3d::UnitZ() * std::cos(a)).normalized();
      double t = w.cast(o, d);
      if (outlier_rate > 0.0 && uni(rng) < outlier_rate) t = 0.02 + uni(rng) * (max_range - 0.02);
      if (t <= max_range && t > 0.02) pts.push_back((o + t * d).cast<float>());
    }
  }
  return pts;
}

}  // namespace test
}  // namespace explorer
}  // namespace scanstop
