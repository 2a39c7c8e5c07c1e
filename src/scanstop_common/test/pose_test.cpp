#include <gtest/gtest.h>

#include <cmath>

#include "scanstop_common/error.h"
#include "scanstop_common/pose.h"

namespace scanstop {
namespace {

constexpr double kEps = 1e-12;

TEST(Pose2D, ComposeMatchesHandComputedValues) {
  // Robot at (1, 2) facing +y; a point 1 m ahead and 0.5 m to its left is at (0.5, 3).
  const Pose2D T_world_robot(1.0, 2.0, M_PI / 2);
  const Pose2D T_robot_point(1.0, 0.5, 0.0);
  const Pose2D T_world_point = T_world_robot * T_robot_point;
  EXPECT_NEAR(T_world_point.x, 0.5, kEps);
  EXPECT_NEAR(T_world_point.y, 3.0, kEps);
  EXPECT_NEAR(T_world_point.yaw, M_PI / 2, kEps);
}

TEST(Pose2D, InverseUndoesTheTransform) {
  const Pose2D T(3.0, -1.0, 0.7);
  const Pose2D I = T * T.inverse();
  EXPECT_NEAR(I.x, 0.0, kEps);
  EXPECT_NEAR(I.y, 0.0, kEps);
  EXPECT_NEAR(I.yaw, 0.0, kEps);
  // Hand-computed: inverse of (2, 0, 90 deg) is (0, 2, -90 deg).
  const Pose2D inv = Pose2D(2.0, 0.0, M_PI / 2).inverse();
  EXPECT_NEAR(inv.x, 0.0, kEps);
  EXPECT_NEAR(inv.y, 2.0, kEps);
  EXPECT_NEAR(inv.yaw, -M_PI / 2, kEps);
}

TEST(Pose2D, BetweenGivesTheRelativeMotion) {
  const Pose2D a(1.0, 1.0, M_PI / 2);
  const Pose2D b(1.0, 3.0, M_PI);
  const Pose2D d = a.between(b);  // 2 m straight ahead, then a left turn
  EXPECT_NEAR(d.x, 2.0, kEps);
  EXPECT_NEAR(d.y, 0.0, kEps);
  EXPECT_NEAR(d.yaw, M_PI / 2, kEps);
  const Pose2D back = a * d;
  EXPECT_NEAR(back.x, b.x, kEps);
  EXPECT_NEAR(back.y, b.y, kEps);
}

TEST(Pose2D, AnglesAreNormalized) {
  EXPECT_NEAR(normalizeAngle(3 * M_PI), M_PI, kEps);
  EXPECT_NEAR(normalizeAngle(-M_PI), M_PI, kEps);
  EXPECT_NEAR(normalizeAngle(-3 * M_PI / 2), M_PI / 2, kEps);
  EXPECT_NEAR((Pose2D(0, 0, 3.0) * Pose2D(0, 0, 3.0)).yaw, 6.0 - 2 * M_PI, kEps);
}

TEST(Pose2D, IsometryRoundTripAndPointTransform) {
  const Pose2D p(0.3, -2.0, -2.5);
  const Eigen::Isometry3d T = p.toIsometry3d();
  const Pose2D q = Pose2D::fromIsometry3d(T);
  EXPECT_NEAR(q.x, p.x, kEps);
  EXPECT_NEAR(q.y, p.y, kEps);
  EXPECT_NEAR(q.yaw, p.yaw, kEps);
  const Eigen::Vector3d v = T * Eigen::Vector3d(1.0, 0.0, 0.5);
  const Eigen::Vector2d w = p.transformPoint(Eigen::Vector2d(1.0, 0.0));
  EXPECT_NEAR(v.x(), w.x(), kEps);
  EXPECT_NEAR(v.y(), w.y(), kEps);
  EXPECT_NEAR(v.z(), 0.5, kEps);
  EXPECT_NEAR(v.x(), 0.3 + std::cos(-2.5), kEps);
}

TEST(Pose2D, ParsesCommandLinePoses) {
  const Pose2D p = parsePose2D("1.5,-2,0.25");
  EXPECT_DOUBLE_EQ(p.x, 1.5);
  EXPECT_DOUBLE_EQ(p.y, -2.0);
  EXPECT_DOUBLE_EQ(p.yaw, 0.25);
  EXPECT_THROW(parsePose2D("1,2"), ConfigError);
  EXPECT_THROW(parsePose2D("1,2,x"), ConfigError);
  EXPECT_THROW(parsePose2D("1,nan,0"), ConfigError);
}

}  // namespace
}  // namespace scanstop
