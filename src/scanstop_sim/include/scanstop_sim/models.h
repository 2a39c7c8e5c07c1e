#pragma once
/// The simulator's models (thesis chapter 6): the rotating URG-04LX geometry and its error model
/// (6.3, chapter 3), and the robot's forward and rotation error models (6.2). Plain config structs
/// with defaults; units in the names.

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <string>

#include "scanstop_common/pose.h"

namespace scanstop {
namespace sim {

/// Geometry of the rotating 2D scanner. The URG's scan plane is vertical and turns about the
/// vertical axis through the scanner centre; the URG looks up: beam step s points at angle
/// (s - 384) * 2 pi / 1024 from +z within the plane, so the 120 deg the URG cannot see point
/// down into the robot (no points below the robot). Plane k of N is turned by k * 180 deg / N
/// about z from the robot's x axis; half a turn covers the whole sphere but the cone below.
struct ScannerConfig {
  double height_m = 0.45;       ///< scanner centre above the floor (base_link z)
  double x_offset_m = 0.0;      ///< scanner centre ahead of the robot centre (base_link x)
  double mount_offset_m = 0.0;  ///< laser optical centre off the rotation axis, along the plane [m]
  int first_step = 44;          ///< URG-04LX AMIN
  int last_step = 725;          ///< URG-04LX AMAX (682 beams)
  int front_step = 384;         ///< AFRT: the step along the plane's "up" axis
  int steps_per_turn = 1024;    ///< ARES
  double min_range_m = 0.02;    ///< DMIN
  double max_range_m = 5.6;     ///< DMAX
  double plane_time_s = 0.1;    ///< time per plane (66.7 ms scan + 33.3 ms return)
  // Mixed pixels (thesis ch. 8, issue #20): a beam has a square footprint beam_divergence wide (in
  // the scan plane and across it); where the footprint covers surfaces at different depths, the
  // reading is their mix. Off by default: it changes the clouds, hence mission results.
  bool mixed_pixels = false;
  double beam_divergence_rad = 2.0 * M_PI / 1024.0;  ///< full width of the footprint [rad]; default one beam step
  double mixed_pixel_threshold_m =
      0.05;                     ///< a sub-ray's hit this far off the centre's surface plane is a depth step [m]
  int mixed_pixel_samples = 4;  ///< sub-rays per footprint axis (n x n sub-rays at a step)

  int beams() const { return last_step - first_step + 1; }
  /// Unit direction of beam `beam` (0-based) in plane `plane` of `planes`, in base_link.
  Eigen::Vector3f direction(int plane, int planes, int beam) const;
  /// Origin of the beams of plane `plane` in base_link.
  Eigen::Vector3f origin(int plane, int planes) const;
  /// Throws ConfigError naming the parameter (sim_node's name: `prefix` + field, e.g. scanner/height_m).
  void validate(const std::string& prefix = "scanner/") const;
};

/// Error model of one range reading (thesis 6.3) and of the transmission (chapter 3).
struct SensorNoiseConfig {
  double p_hit = 1.0;          ///< relative probability of a normal reading
  double p_random = 0.0;       ///< ... of a random reading, uniform over [min, max] range
  double p_max = 0.0;          ///< ... of a max-range reading (invalid: NaN in the cloud)
  double sigma_near_m = 0.0;   ///< standard deviation of a normal reading up to 1 m [m]
  double sigma_far_rel = 0.0;  ///< ... relative to the range beyond 1 m
  double p_plane_loss = 0.0;   ///< probability that a whole plane is lost in transmission
  /// Throws ConfigError naming the parameter (`prefix` + field, e.g. profiles/thesis/sensor/p_hit).
  void validate(const std::string& prefix = "sensor/") const;
};

/// Robot motion error model (thesis 6.2). Odometry always reports the commanded motion; the true
/// motion differs.
struct MotionConfig {
  // forward motion
  double curvature_per_m = 0.0;         ///< systematic curvature of a straight motion [1/m]
  double curvature_sigma_per_m = 0.0;   ///< its Gaussian deviation [1/m]
  double distance_error_rel = 0.0;      ///< systematic relative distance error
  double distance_sigma_rel = 0.0;      ///< its Gaussian deviation
  double finish_angle_rad = 0.0;        ///< systematic rotation at the end of a forward motion [rad]
  double finish_angle_sigma_rad = 0.0;  ///< its Gaussian deviation [rad]
  // rotation
  double rotation_error_rel = 0.0;                 ///< systematic relative angle error
  double rotation_sigma_rel = 0.0;                 ///< its Gaussian deviation
  double rotation_position_sigma_m_per_rad = 0.0;  ///< Gaussian position change per radian turned [m/rad]
  // speeds (modelled durations)
  double linear_speed_mps = 0.2;     ///< [m/s]
  double angular_speed_radps = 0.5;  ///< [rad/s]
  /// Throws ConfigError naming the parameter: error fields as `error_prefix` + field (e.g.
  /// profiles/thesis/motion/curvature_per_m), the speeds as `speed_prefix` + field (motion/linear_speed_mps).
  void validate(const std::string& error_prefix = "motion/", const std::string& speed_prefix = "motion/") const;
};

/// A named set of error models.
struct ErrorProfile {
  SensorNoiseConfig sensor;
  MotionConfig motion;
};

/// "perfect" (no errors) or "thesis" (the thesis' sensor specification and a Pioneer-like motion
/// model); throws ConfigError for another name.
ErrorProfile makeProfile(const std::string& name);

/// The true motion of a forward command of `distance_m`: an arc with curvature, a length error and
/// a finishing rotation; `s_max_m` (when >= 0) cuts the arc at that true path length (collision).
/// Returns the relative true motion T_before_after.
struct ForwardSample {
  double true_length_m = 0.0;
  double curvature_per_m = 0.0;
  double finish_angle_rad = 0.0;
  /// The relative pose after travelling s metres along the arc (without the finishing rotation).
  Pose2D along(double s) const;
};
ForwardSample sampleForward(const MotionConfig& m, double distance_m, std::mt19937_64& rng);

/// The true relative motion of a rotation command (T_before_after).
Pose2D sampleRotation(const MotionConfig& m, double angle_rad, std::mt19937_64& rng);

/// A simulated range reading: NaN for an invalid one (no return, max-range case, out of range).
float sampleRange(const SensorNoiseConfig& noise, const ScannerConfig& scanner, float true_range_m,
                  std::mt19937_64& rng);
/// The same with a caller-owned standard normal distribution (mean 0, sigma 1): a scan keeps one
/// per plane, so the second variate the polar method makes is used instead of thrown away.
float sampleRange(const SensorNoiseConfig& noise, const ScannerConfig& scanner, float true_range_m,
                  std::mt19937_64& rng, std::normal_distribution<double>& standard_normal);

}  // namespace sim
}  // namespace scanstop
