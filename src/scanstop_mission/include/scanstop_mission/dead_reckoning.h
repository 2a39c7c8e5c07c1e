#pragma once
/// How far the robot may truly be from where odometry says, since the last scan: the leg check's
/// model of what odometry cannot see. Between scans the mission drives by odometry alone; a
/// rotation's own error, the slow heading drift of straight motions (unequal wheels) and the
/// odometry's scale error all pass unseen, and a heading error turns into a lateral error on every
/// metre driven after it (furnished_2: 288 deg of turns and 4.3 m over five legs after a scan put
/// the robot 0.31 m beside its estimate, into a door jamb the plan passed 0.5 m away), and a turn
/// on the spot moves the wheels' axle (office_loop seed 4: 12.7 cm after a 170 deg turn, then 0.9 m
/// into a leg beside a wall). ROS-free.

#include "scanstop_common/pose.h"

namespace scanstop {
namespace mission {

/// The error bounds of the odometry (defaults: the thesis' motion profile with a margin).
struct DeadReckoningModel {
  double turn_error = 0.03;        ///< heading error per radian turned [rad/rad] (thesis: 2 % + 1 %)
  double drift_rad_per_m = 0.015;  ///< heading drift per metre driven [rad/m] (thesis: curvature 0.01 + 0.005 1/m)
  double distance_error = 0.04;    ///< position error per metre driven [m/m] (thesis: scale 3 % + 1 %)
  /// position error per radian turned [m/rad]: a rotation on the spot does not stay on the spot
  /// (the thesis' simulator: a Gaussian of 0.01 m/rad per axis; this is its 3 sigma)
  double turn_position_m_per_rad = 0.03;
};

/// The accumulated bounds since the last reset (a scan): a heading bound and a position bound.
class DeadReckoning {
 public:
  /// The heading bound is capped here [rad] (beyond it the robot would rather scan anyway).
  static constexpr double kMaxHeadingRad = 0.5;

  explicit DeadReckoning(const DeadReckoningModel& model = {}) : model_(model) {}

  /// Forgets the motions: the robot knows where it is (a scan was just taken).
  void reset();
  /// Books one motion as odometry measured it: `delta` is the pose after it in the pose before.
  /// Its translation is driven first (at the heading bound so far), then its rotation turned (the
  /// turn moves the position by up to turn_position_m_per_rad per radian).
  void add(const Pose2D& delta);

  /// How far the true heading may be off the odometry's [rad], at most kMaxHeadingRad.
  double headingBoundRad() const;
  /// How far the true position may be off the odometry's [m].
  double positionBoundM() const { return position_m_; }
  /// The radius a disc of `radius_m` must have at `ahead_m` metres straight ahead (along the
  /// estimated heading) to hold the true disc there [m].
  double widenedRadius(double radius_m, double ahead_m) const;

  double drivenM() const { return driven_m_; }      ///< driven since the reset [m]
  double turnedRad() const { return turned_rad_; }  ///< |turns| summed since the reset [rad]
  const DeadReckoningModel& model() const { return model_; }

 private:
  DeadReckoningModel model_;
  double driven_m_ = 0.0;
  double turned_rad_ = 0.0;
  double position_m_ = 0.0;
};

}  // namespace mission
}  // namespace scanstop
