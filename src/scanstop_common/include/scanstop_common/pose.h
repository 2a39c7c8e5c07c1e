#pragma once
/// 2D (x, y, yaw) and 3D rigid poses and their conversions.
///
/// Convention: a pose T_a_b maps points from frame b into frame a (p_a = T_a_b * p_b).
/// Units: metres and radians; yaw counter-clockwise about +z (REP-103).

#include <Eigen/Geometry>
#include <string>

namespace scanstop {

/// Wraps an angle to (-pi, pi] [rad].
double normalizeAngle(double angle_rad);

/// A planar pose: position (x, y) [m] and heading yaw [rad].
struct Pose2D {
  double x = 0.0;
  double y = 0.0;
  double yaw = 0.0;

  Pose2D() = default;
  Pose2D(double x_m, double y_m, double yaw_rad) : x(x_m), y(y_m), yaw(yaw_rad) {}

  /// this * other: other expressed in this pose's frame, composed (T_a_c = T_a_b * T_b_c).
  Pose2D operator*(const Pose2D& other) const;
  /// The inverse pose (T_b_a from T_a_b).
  Pose2D inverse() const;
  /// Maps a point of this pose's frame into the parent frame.
  Eigen::Vector2d transformPoint(const Eigen::Vector2d& p) const;
  /// The relative pose from this to other: this.inverse() * other.
  Pose2D between(const Pose2D& other) const;

  Eigen::Isometry3d toIsometry3d() const;
  Eigen::Isometry3f toIsometry3f() const { return toIsometry3d().cast<float>(); }
  /// Projects a 3D pose onto the plane (keeps x, y and the heading of the x axis).
  static Pose2D fromIsometry3d(const Eigen::Isometry3d& T);

  bool isFinite() const;
  std::string toString() const;
};

/// Yaw [rad] of the x axis of a rotation projected onto the xy plane.
double yawOf(const Eigen::Matrix3d& R);

/// Parses "x,y,yaw" (metres, metres, radians) as a command-line tools take it; throws ConfigError.
Pose2D parsePose2D(const std::string& text);

}  // namespace scanstop
