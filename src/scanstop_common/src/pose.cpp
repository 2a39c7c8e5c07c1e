#include "scanstop_common/pose.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "scanstop_common/error.h"

namespace scanstop {

double normalizeAngle(double angle_rad) {
  double a = std::fmod(angle_rad, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  if (a > M_PI) a -= 2.0 * M_PI;
  return a;
}

Pose2D Pose2D::operator*(const Pose2D& other) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return Pose2D(x + c * other.x - s * other.y, y + s * other.x + c * other.y, normalizeAngle(yaw + other.yaw));
}

Pose2D Pose2D::inverse() const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return Pose2D(-c * x - s * y, s * x - c * y, normalizeAngle(-yaw));
}

Eigen::Vector2d Pose2D::transformPoint(const Eigen::Vector2d& p) const {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return Eigen::Vector2d(x + c * p.x() - s * p.y(), y + s * p.x() + c * p.y());
}

Pose2D Pose2D::between(const Pose2D& other) const { return inverse() * other; }

Eigen::Isometry3d Pose2D::toIsometry3d() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

double yawOf(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

Pose2D Pose2D::fromIsometry3d(const Eigen::Isometry3d& T) {
  return Pose2D(T.translation().x(), T.translation().y(), yawOf(T.linear()));
}

bool Pose2D::isFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(yaw); }

std::string Pose2D::toString() const {
  std::ostringstream out;
  out << "(x=" << x << " m, y=" << y << " m, yaw=" << yaw << " rad)";
  return out.str();
}

Pose2D parsePose2D(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      size_t used = 0;
      values.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw ConfigError("pose '" + text + "': '" + item + "' is not a number (expected x,y,yaw)");
    }
  }
  if (values.size() != 3) throw ConfigError("pose '" + text + "': expected three values x,y,yaw");
  Pose2D p(values[0], values[1], values[2]);
  if (!p.isFinite()) throw ConfigError("pose '" + text + "': values must be finite");
  return p;
}

}  // namespace scanstop
