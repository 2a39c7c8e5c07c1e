#include "scanstop_sim/models.h"

#include <cmath>
#include <limits>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"

namespace scanstop {
namespace sim {

Eigen::Vector3f ScannerConfig::direction(int plane, int planes, int beam) const {
  const double phi = M_PI * plane / planes;                                             // plane turn about z
  const double theta = (first_step + beam - front_step) * 2.0 * M_PI / steps_per_turn;  // from +z
  const double h = std::sin(theta);
  return Eigen::Vector3f(static_cast<float>(h * std::cos(phi)), static_cast<float>(h * std::sin(phi)),
                         static_cast<float>(std::cos(theta)));
}

Eigen::Vector3f ScannerConfig::origin(int plane, int planes) const {
  const double phi = M_PI * plane / planes;
  return Eigen::Vector3f(static_cast<float>(x_offset_m + mount_offset_m * std::cos(phi)),
                         static_cast<float>(mount_offset_m * std::sin(phi)), static_cast<float>(height_m));
}

void ScannerConfig::validate(const std::string& p) const {
  requireInRange(p + "height_m", height_m, 0.05, 3.0, "m");
  requireInRange(p + "x_offset_m", x_offset_m, -1.0, 1.0, "m");
  requireInRange(p + "mount_offset_m", mount_offset_m, -0.5, 0.5, "m");
  requireInRange(p + "min_range_m", min_range_m, 0.0, 1.0, "m");
  requireInRange(p + "max_range_m", max_range_m, min_range_m + 0.01, 100.0, "m");
  requireInRange(p + "plane_time_s", plane_time_s, 0.001, 10.0, "s");
  // The candidates for mixed pixels are found from the neighbouring beams: a footprint wider than
  // two beam steps would reach past them.
  requireInRange(p + "beam_divergence_rad", beam_divergence_rad, 1e-4, 4.0 * M_PI / steps_per_turn, "rad");
  requireInRange(p + "mixed_pixel_threshold_m", mixed_pixel_threshold_m, 0.005, 1.0, "m");
  requireInRange(p + "mixed_pixel_samples", mixed_pixel_samples, 2, 8);
  if (first_step < 0 || last_step <= first_step || last_step >= steps_per_turn)
    throw ConfigError(p + "first_step = " + std::to_string(first_step) + ", " + p +
                      "last_step = " + std::to_string(last_step) +
                      ": need 0 <= first_step < last_step < steps_per_turn (" + std::to_string(steps_per_turn) + ")");
}

void SensorNoiseConfig::validate(const std::string& p) const {
  requireInRange(p + "p_hit", p_hit, 0.0, 1.0);
  requireInRange(p + "p_random", p_random, 0.0, 1.0);
  requireInRange(p + "p_max", p_max, 0.0, 1.0);
  if (p_hit + p_random + p_max <= 0.0)
    throw ConfigError("parameters '" + p + "p_hit' + '" + p + "p_random' + '" + p +
                      "p_max' = 0: their sum must be > 0");
  requireInRange(p + "sigma_near_m", sigma_near_m, 0.0, 1.0, "m");
  requireInRange(p + "sigma_far_rel", sigma_far_rel, 0.0, 1.0);
  requireInRange(p + "p_plane_loss", p_plane_loss, 0.0, 1.0);
}

void MotionConfig::validate(const std::string& p, const std::string& sp) const {
  requireInRange(p + "curvature_per_m", curvature_per_m, -1.0, 1.0, "1/m");
  requireInRange(p + "curvature_sigma_per_m", curvature_sigma_per_m, 0.0, 1.0, "1/m");
  requireInRange(p + "distance_error_rel", distance_error_rel, -0.5, 0.5);
  requireInRange(p + "distance_sigma_rel", distance_sigma_rel, 0.0, 0.5);
  requireInRange(p + "finish_angle_rad", finish_angle_rad, -0.5, 0.5, "rad");
  requireInRange(p + "finish_angle_sigma_rad", finish_angle_sigma_rad, 0.0, 0.5, "rad");
  requireInRange(p + "rotation_error_rel", rotation_error_rel, -0.5, 0.5);
  requireInRange(p + "rotation_sigma_rel", rotation_sigma_rel, 0.0, 0.5);
  requireInRange(p + "rotation_position_sigma_m_per_rad", rotation_position_sigma_m_per_rad, 0.0, 1.0, "m/rad");
  // A Pioneer 2 DX drives at most 1.5 m/s and turns at most 500 deg/s (8.7 rad/s).
  requireInRange(sp + "linear_speed_mps", linear_speed_mps, 0.01, 1.5, "m/s");
  requireInRange(sp + "angular_speed_radps", angular_speed_radps, 0.01, 8.7, "rad/s");
}

ErrorProfile makeProfile(const std::string& name) {
  ErrorProfile p;
  if (name == "perfect") return p;
  if (name != "thesis") throw ConfigError("error profile '" + name + "' must be one of perfect, thesis");
  // Sensor: the URG-04LX specification (10 mm up to 1 m, 1 % beyond), occasional random and
  // max-range readings, and whole planes lost in transmission as on the real platform.
  p.sensor.p_hit = 0.97;
  p.sensor.p_random = 0.01;
  p.sensor.p_max = 0.02;
  p.sensor.sigma_near_m = 0.01;
  p.sensor.sigma_far_rel = 0.01;
  p.sensor.p_plane_loss = 0.02;
  // Motion: slightly different wheel radii (curvature), a 3 % odometry scale error, a small turn at
  // the end of every straight motion, 2 % rotation error and some drift while turning.
  p.motion.curvature_per_m = 0.01;
  p.motion.curvature_sigma_per_m = 0.005;
  p.motion.distance_error_rel = 0.03;
  p.motion.distance_sigma_rel = 0.01;
  p.motion.finish_angle_rad = 0.5 * M_PI / 180.0;
  p.motion.finish_angle_sigma_rad = 0.3 * M_PI / 180.0;
  p.motion.rotation_error_rel = 0.02;
  p.motion.rotation_sigma_rel = 0.01;
  p.motion.rotation_position_sigma_m_per_rad = 0.01;
  return p;
}

Pose2D ForwardSample::along(double s) const {
  const double k = curvature_per_m;
  if (std::abs(k) < 1e-9) return Pose2D(s, 0.0, 0.0);
  return Pose2D(std::sin(k * s) / k, (1.0 - std::cos(k * s)) / k, k * s);
}

ForwardSample sampleForward(const MotionConfig& m, double distance_m, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  ForwardSample f;
  const double sign = distance_m < 0 ? -1.0 : 1.0;
  f.curvature_per_m = sign * (m.curvature_per_m + m.curvature_sigma_per_m * n01(rng));
  f.true_length_m = distance_m * (1.0 + m.distance_error_rel + m.distance_sigma_rel * n01(rng));
  f.finish_angle_rad = m.finish_angle_rad + m.finish_angle_sigma_rad * n01(rng);
  return f;
}

Pose2D sampleRotation(const MotionConfig& m, double angle_rad, std::mt19937_64& rng) {
  std::normal_distribution<double> n01(0.0, 1.0);
  const double turned = angle_rad * (1.0 + m.rotation_error_rel + m.rotation_sigma_rel * n01(rng));
  const double sigma = m.rotation_position_sigma_m_per_rad * std::abs(angle_rad);
  return Pose2D(sigma * n01(rng), sigma * n01(rng), turned);
}

float sampleRange(const SensorNoiseConfig& noise, const ScannerConfig& scanner, float true_range_m,
                  std::mt19937_64& rng) {
  std::normal_distribution<double> standard_normal(0.0, 1.0);
  return sampleRange(noise, scanner, true_range_m, rng, standard_normal);
}

float sampleRange(const SensorNoiseConfig& noise, const ScannerConfig& scanner, float true_range_m,
                  std::mt19937_64& rng, std::normal_distribution<double>& standard_normal) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const double total = noise.p_hit + noise.p_random + noise.p_max;
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  // Only hits possible (perfect sensor): no draw needed.
  const double pick = (noise.p_random + noise.p_max > 0.0) ? u01(rng) * total : 0.0;
  if (pick >= noise.p_hit + noise.p_random) return kNaN;  // max-range reading: the URG reports no return
  if (pick >= noise.p_hit) {
    return static_cast<float>(scanner.min_range_m + u01(rng) * (scanner.max_range_m - scanner.min_range_m));
  }
  if (!std::isfinite(true_range_m) || true_range_m > scanner.max_range_m || true_range_m < scanner.min_range_m)
    return kNaN;
  const double sigma = true_range_m <= 1.0 ? noise.sigma_near_m : noise.sigma_far_rel * true_range_m;
  if (sigma <= 0.0) return true_range_m;
  const double r = true_range_m + sigma * standard_normal(rng);
  return (r < scanner.min_range_m || r > scanner.max_range_m) ? kNaN : static_cast<float>(r);
}

}  // namespace sim
}  // namespace scanstop
