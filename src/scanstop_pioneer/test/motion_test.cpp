// MotionController against a simple simulated robot: reaching targets, overshoot reported, stall,
// bumper, timeout and disabled motors abort with a reason.
#include <gtest/gtest.h>

#include <cmath>

#include "scanstop_pioneer/motion_controller.h"

namespace {

using namespace scanstop::pioneer;
using scanstop::Pose2D;

/// A unicycle with acceleration limits, sampled at 10 Hz like SIPs.
struct FakeRobot {
  MotionSample s;
  double set_v = 0, set_w = 0;
  double accel = 0.3, rot_accel = 1.745;
  bool blocked = false;
  void apply(const MotionCommand& c) {
    set_v = c.stop ? 0.0 : c.v_mps;
    set_w = c.stop ? 0.0 : c.w_radps;
    if (c.emergency) s.v_mps = s.w_radps = 0.0;
  }
  void step(double dt) {
    auto approach = [](double v, double t, double d) { return v < t ? std::min(t, v + d) : std::max(t, v - d); };
    s.v_mps = blocked ? 0.0 : approach(s.v_mps, set_v, accel * dt);
    s.w_radps = blocked ? 0.0 : approach(s.w_radps, set_w, rot_accel * dt);
    s.pose = Pose2D(s.pose.x + s.v_mps * dt * std::cos(s.pose.yaw), s.pose.y + s.v_mps * dt * std::sin(s.pose.yaw),
                    scanstop::normalizeAngle(s.pose.yaw + s.w_radps * dt));
    s.moving = std::abs(s.v_mps) > 1e-9 || std::abs(s.w_radps) > 1e-9 || std::abs(set_v) > 0 || std::abs(set_w) > 0;
    s.t_s += dt;
  }
};

MotionController run(FakeRobot& robot, MotionKind kind, double target, const MotionConfig& config = MotionConfig(),
                     int max_steps = 2000) {
  MotionController c(config, kind, target, robot.s);
  for (int i = 0; i < max_steps && !c.finished(); ++i) {
    robot.step(0.1);
    robot.apply(c.update(robot.s));
  }
  return c;
}

TEST(Motion, ForwardReachesTheDistanceAndReportsOdometry) {
  FakeRobot robot;
  robot.s.pose = Pose2D(1.0, -1.0, M_PI / 2);
  const MotionController c = run(robot, MotionKind::kForward, 1.0);
  ASSERT_TRUE(c.finished());
  EXPECT_TRUE(c.success()) << c.message();
  EXPECT_FALSE(c.collision());
  EXPECT_NEAR(c.achieved(), 1.0, 0.02);
  // The reported value is what odometry measured, overshoot included.
  EXPECT_NEAR(c.achieved(), std::hypot(robot.s.pose.x - 1.0, robot.s.pose.y + 1.0), 1e-9);
  EXPECT_NEAR(robot.s.pose.y, 0.0, 0.02);
  EXPECT_LT(std::abs(robot.s.v_mps), 1e-9);  // stopped before reporting
  EXPECT_GT(c.durationS(), 5.0);             // 1 m at 0.2 m/s
  EXPECT_LT(c.durationS(), c.timeoutS());
}

TEST(Motion, BackwardDistanceIsNegative) {
  FakeRobot robot;
  const MotionController c = run(robot, MotionKind::kForward, -0.5);
  EXPECT_TRUE(c.success()) << c.message();
  EXPECT_NEAR(c.achieved(), -0.5, 0.02);
  EXPECT_NEAR(robot.s.pose.x, -0.5, 0.02);
}

TEST(Motion, RotationUnwrapsBeyondPi) {
  for (double target : {M_PI / 2, -M_PI / 3, 1.5 * M_PI, -2.0 * M_PI}) {
    FakeRobot robot;
    robot.s.pose.yaw = 3.0;  // start close to the +-pi seam
    const MotionController c = run(robot, MotionKind::kRotate, target);
    EXPECT_TRUE(c.success()) << target << ": " << c.message();
    EXPECT_NEAR(c.achieved(), target, 0.02) << target;
    EXPECT_NEAR(scanstop::normalizeAngle(robot.s.pose.yaw - 3.0 - c.achieved()), 0.0, 1e-9);
  }
}

TEST(Motion, StallAbortsWithCollision) {
  FakeRobot robot;
  MotionController c(MotionConfig(), MotionKind::kForward, 1.0, robot.s);
  for (int i = 0; i < 200 && !c.finished(); ++i) {
    robot.step(0.1);
    if (robot.s.t_s > 1.0) {
      robot.blocked = true;
      robot.s.left_stall = true;
    }
    robot.apply(c.update(robot.s));
  }
  ASSERT_TRUE(c.finished());
  EXPECT_FALSE(c.success());
  EXPECT_TRUE(c.collision());
  EXPECT_EQ(c.outcome(), MotionOutcome::kStall);
  EXPECT_NE(c.message().find("left wheel"), std::string::npos) << c.message();
  EXPECT_LT(c.achieved(), 0.3);
  EXPECT_LT(c.durationS(), 3.0);
}

TEST(Motion, FrontBumperAbortsForwardButNotBackward) {
  FakeRobot robot;
  robot.s.front_bumpers = 0x04;
  MotionController fwd(MotionConfig(), MotionKind::kForward, 1.0, robot.s);
  robot.step(0.1);
  const MotionCommand cmd = fwd.update(robot.s);
  EXPECT_TRUE(cmd.stop);
  EXPECT_TRUE(cmd.emergency);
  EXPECT_EQ(fwd.outcome(), MotionOutcome::kBumper);
  EXPECT_TRUE(fwd.collision());
  EXPECT_NE(fwd.message().find("front bumper"), std::string::npos) << fwd.message();
  // Backing away from the obstacle is allowed.
  FakeRobot back;
  back.s.front_bumpers = 0x04;
  const MotionController c = run(back, MotionKind::kForward, -0.3);
  EXPECT_TRUE(c.success()) << c.message();
}

TEST(Motion, FrozenOdometryTimesOut) {
  MotionConfig config;
  config.timeout_extra_s = 1.0;
  FakeRobot robot;
  MotionController c(config, MotionKind::kRotate, 1.0, robot.s);
  MotionSample frozen = robot.s;
  for (int i = 0; i < 1000 && !c.finished(); ++i) {
    frozen.t_s += 0.1;
    frozen.moving = false;
    c.update(frozen);
  }
  ASSERT_TRUE(c.finished());
  EXPECT_EQ(c.outcome(), MotionOutcome::kTimeout);
  EXPECT_FALSE(c.collision());
  EXPECT_NE(c.message().find("timeout"), std::string::npos);
  EXPECT_NEAR(c.durationS(), c.timeoutS(), 0.25);
}

TEST(Motion, DisabledMotorsAbort) {
  FakeRobot robot;
  robot.s.motors_enabled = false;
  robot.blocked = true;
  const MotionController c = run(robot, MotionKind::kForward, 0.5);
  EXPECT_EQ(c.outcome(), MotionOutcome::kMotorsDisabled);
  EXPECT_NE(c.message().find("motors disabled"), std::string::npos);
}

TEST(Motion, ExternalAbortAndInvalidTargets) {
  FakeRobot robot;
  MotionController c(MotionConfig(), MotionKind::kForward, 1.0, robot.s);
  robot.step(0.1);
  c.update(robot.s);
  c.abort("link to the robot lost", robot.s.t_s);
  EXPECT_TRUE(c.finished());
  EXPECT_EQ(c.outcome(), MotionOutcome::kAborted);
  EXPECT_NE(c.message().find("link to the robot lost"), std::string::npos);
  EXPECT_THROW(MotionController(MotionConfig(), MotionKind::kForward, 6.0, robot.s), std::invalid_argument);
  EXPECT_THROW(MotionController(MotionConfig(), MotionKind::kRotate, NAN, robot.s), std::invalid_argument);
  const MotionController zero(MotionConfig(), MotionKind::kRotate, 0.0, robot.s);
  EXPECT_TRUE(zero.finished());
  EXPECT_TRUE(zero.success());
}

TEST(Motion, ConfigValidationNamesTheParameter) {
  MotionConfig config;
  config.min_linear_speed_mps = 0.5;  // above the cruise speed
  try {
    config.validate();
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("motion/min_linear_speed"), std::string::npos) << e.what();
  }
}

}  // namespace
