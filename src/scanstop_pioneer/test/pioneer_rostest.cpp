// rostest of pioneer_driver against pioneer_emulator on a pseudo-terminal: the first connect meets
// a session left open; then motions, cmd_vel timeout, and every injected fault (corrupt checksums,
// dropped bytes, garbage, stall, bumper, frozen encoders, silence, disconnect). Each must either be
// survived or reported clearly, no call may hang, and odom must never carry garbage.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <fcntl.h>
#include <geometry_msgs/Twist.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <scanstop_msgs/Forward.h>
#include <scanstop_msgs/Rotate.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <future>
#include <limits>
#include <mutex>

#include "scanstop_pioneer/pioneer_driver_node.h"

namespace {

using scanstop::pioneer::DriverConfig;
using scanstop::pioneer::PioneerDriverNode;
namespace ros_params = scanstop::ros_params;
using scanstop::ConfigError;

/// Watches odom: counts messages and records anything that would be garbage.
struct OdomWatch {
  std::mutex mutex;
  nav_msgs::Odometry last;
  ros::WallTime last_wall;
  int count = 0;
  int bad = 0;
  double max_step = 0.0;
  std::string first_problem;
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    std::string problem;
    const auto& p = m->pose.pose.position;
    const auto& q = m->pose.pose.orientation;
    const double qn = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (m->header.frame_id != "odom" || m->child_frame_id != "base_link")
      problem = "wrong frames";
    else if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(qn) || std::abs(qn - 1.0) > 1e-6)
      problem = "non-finite or unnormalised pose";
    else if (std::abs(m->twist.twist.linear.x) > 0.6 || std::abs(m->twist.twist.angular.z) > 1.5)
      problem = "implausible velocity";
    if (count > 0 && problem.empty()) {
      const double step = std::hypot(p.x - last.pose.pose.position.x, p.y - last.pose.pose.position.y);
      max_step = std::max(max_step, step);
      if (step > 0.1) problem = "odometry jumped " + std::to_string(step) + " m between two messages";
    }
    if (!problem.empty()) {
      ++bad;
      if (first_problem.empty()) first_problem = problem;
    }
    last = *m;
    last_wall = ros::WallTime::now();
    ++count;
  }
  int messages() {
    std::lock_guard<std::mutex> lock(mutex);
    return count;
  }
  nav_msgs::Odometry latest() {
    std::lock_guard<std::mutex> lock(mutex);
    return last;
  }
};

struct DiagWatch {
  std::mutex mutex;
  diagnostic_msgs::DiagnosticStatus status;
  bool have = false;
  void onDiag(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    for (const auto& s : m->status) {
      if (s.name.find("Pioneer base") == std::string::npos) continue;
      std::lock_guard<std::mutex> lock(mutex);
      status = s;
      have = true;
    }
  }
  std::string value(const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& kv : status.values)
      if (kv.key == key) return kv.value;
    return "";
  }
  double number(const std::string& key) {
    const std::string v = value(key);
    return v.empty() ? -1.0 : std::stod(v);
  }
};

OdomWatch* g_odom = nullptr;
DiagWatch* g_diag = nullptr;

void inject(const std::string& line) {
  ros::NodeHandle pnh("~");
  std::string control;
  ASSERT_TRUE(pnh.getParam("control", control));
  const int fd = ::open(control.c_str(), O_WRONLY | O_NONBLOCK);
  ASSERT_GE(fd, 0) << "cannot open the emulator's control FIFO " << control;
  const std::string text = line + "\n";
  ASSERT_EQ(::write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(fd);
  ros::WallDuration(0.2).sleep();  // the emulator polls its FIFO every 100 ms
}

scanstop_msgs::Rotate rotate(double angle) {
  scanstop_msgs::Rotate srv;
  srv.request.angle_rad = angle;
  EXPECT_TRUE(ros::service::call("base/rotate", srv));
  return srv;
}

scanstop_msgs::Forward forward(double distance) {
  scanstop_msgs::Forward srv;
  srv.request.distance_m = distance;
  EXPECT_TRUE(ros::service::call("base/forward", srv));
  return srv;
}

/// Waits until odom flows again (n new messages) within timeout_s.
bool odomFlows(int n, double timeout_s) {
  const int start = g_odom->messages();
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::WallTime::now() < end) {
    if (g_odom->messages() >= start + n) return true;
    ros::WallDuration(0.05).sleep();
  }
  return false;
}

TEST(PioneerDriver, A_ConnectsClosingTheSessionLeftOpen) {
  ASSERT_TRUE(ros::service::waitForService("base/forward", ros::Duration(20.0)));
  ASSERT_TRUE(odomFlows(5, 20.0)) << "no odom from pioneer_driver";
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(5.0);
  while (ros::WallTime::now() < end && !g_diag->have) ros::WallDuration(0.1).sleep();
  ros::WallDuration(2.2).sleep();  // a full diagnostics period after connecting (SIP rate)
  EXPECT_GE(g_diag->number("recoveries (session still open)"), 1.0);
  EXPECT_EQ(g_diag->value("link"), "connected");
  EXPECT_EQ(g_diag->value("robot"), "scanstop-emulator (Pioneer p2dx)");
  EXPECT_NEAR(g_diag->number("SIP rate [Hz]"), 10.0, 1.5);
  EXPECT_EQ(g_diag->status.level, diagnostic_msgs::DiagnosticStatus::OK) << g_diag->status.message;
}

TEST(PioneerDriver, B_ConfigFileEqualsTheCodeDefaults) {
  ros_params::ParamReader params(ros::NodeHandle("/pioneer_driver"), "pioneer_driver");
  const DriverConfig read = PioneerDriverNode::readParameters(params).driver;
  DriverConfig d;
  EXPECT_EQ(read.baud, d.baud);
  EXPECT_EQ(read.robot.subclass, d.robot.subclass);
  EXPECT_DOUBLE_EQ(read.robot.angle_conv_rad, d.robot.angle_conv_rad);
  EXPECT_DOUBLE_EQ(read.robot.dist_conv_mm, d.robot.dist_conv_mm);
  EXPECT_DOUBLE_EQ(read.robot.vel_conv, d.robot.vel_conv);
  EXPECT_DOUBLE_EQ(read.robot.range_conv_mm, d.robot.range_conv_mm);
  EXPECT_DOUBLE_EQ(read.robot.diff_conv, d.robot.diff_conv);
  EXPECT_DOUBLE_EQ(read.robot.max_velocity_mps, d.robot.max_velocity_mps);
  EXPECT_DOUBLE_EQ(read.robot.max_rot_velocity_radps, d.robot.max_rot_velocity_radps);
  EXPECT_DOUBLE_EQ(read.client.reply_timeout_s, d.client.reply_timeout_s);
  EXPECT_EQ(read.client.sync_attempts, d.client.sync_attempts);
  EXPECT_DOUBLE_EQ(read.client.close_wait_s, d.client.close_wait_s);
  EXPECT_DOUBLE_EQ(read.sip_timeout_s, d.sip_timeout_s);
  EXPECT_DOUBLE_EQ(read.reconnect_period_s, d.reconnect_period_s);
  EXPECT_DOUBLE_EQ(read.pulse_period_s, d.pulse_period_s);
  EXPECT_DOUBLE_EQ(read.cmd_vel_timeout_s, d.cmd_vel_timeout_s);
  EXPECT_DOUBLE_EQ(read.max_linear_speed_mps, d.max_linear_speed_mps);
  EXPECT_DOUBLE_EQ(read.max_angular_speed_radps, d.max_angular_speed_radps);
  const auto& m = read.motion;
  const auto& dm = d.motion;
  EXPECT_DOUBLE_EQ(m.linear_speed_mps, dm.linear_speed_mps);
  EXPECT_DOUBLE_EQ(m.angular_speed_radps, dm.angular_speed_radps);
  EXPECT_DOUBLE_EQ(m.min_linear_speed_mps, dm.min_linear_speed_mps);
  EXPECT_DOUBLE_EQ(m.min_angular_speed_radps, dm.min_angular_speed_radps);
  EXPECT_DOUBLE_EQ(m.linear_decel_mps2, dm.linear_decel_mps2);
  EXPECT_DOUBLE_EQ(m.angular_decel_radps2, dm.angular_decel_radps2);
  EXPECT_DOUBLE_EQ(m.approach_distance_m, dm.approach_distance_m);
  EXPECT_DOUBLE_EQ(m.approach_angle_rad, dm.approach_angle_rad);
  EXPECT_DOUBLE_EQ(m.distance_tolerance_m, dm.distance_tolerance_m);
  EXPECT_DOUBLE_EQ(m.angle_tolerance_rad, dm.angle_tolerance_rad);
  EXPECT_DOUBLE_EQ(m.timeout_factor, dm.timeout_factor);
  EXPECT_DOUBLE_EQ(m.timeout_extra_s, 2.0);  // overridden by the test launch file
  EXPECT_DOUBLE_EQ(m.stall_time_s, dm.stall_time_s);
  EXPECT_DOUBLE_EQ(m.motors_disabled_time_s, dm.motors_disabled_time_s);
  EXPECT_DOUBLE_EQ(m.settle_timeout_s, dm.settle_timeout_s);
  EXPECT_DOUBLE_EQ(m.max_forward_m, dm.max_forward_m);
  EXPECT_NEAR(m.max_rotate_rad, dm.max_rotate_rad, 1e-4);
  // Every key of config/pioneer.yaml is one the node reads (no typos).
  const auto unknown = params.unknown();
  EXPECT_TRUE(unknown.empty()) << unknown.front();
  // A bad value is refused with the parameter's name.
  ros::NodeHandle bad("/bad_pioneer");
  bad.setParam("port", "/dev/null");
  bad.setParam("motion/linear_speed_mps", -1.0);
  try {
    ros_params::ParamReader bad_params(bad, "pioneer_driver");
    PioneerDriverNode::readParameters(bad_params);
    FAIL() << "expected ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("motion/linear_speed_mps"), std::string::npos) << e.what();
  }
  // A misspelt parameter: refused, named, with the name it was meant to be.
  bad.setParam("motion/linear_speed_mps", 0.1);
  bad.setParam("motion/linear_sped_mps", 0.1);
  ros_params::ParamReader typo_params(bad, "pioneer_driver");
  PioneerDriverNode::readParameters(typo_params);
  ASSERT_EQ(typo_params.unknown().size(), 1u);
  EXPECT_EQ(typo_params.unknown()[0], "/bad_pioneer/motion/linear_sped_mps");
  try {
    typo_params.rejectUnknown();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown parameter '/bad_pioneer/motion/linear_sped_mps' (did you mean "
                                         "'motion/linear_speed_mps'?)"),
              std::string::npos)
        << e.what();
  }
}

TEST(PioneerDriver, C_RotateAndForward) {
  const auto r = rotate(M_PI / 2);
  ASSERT_TRUE(r.response.success) << r.response.message;
  EXPECT_NEAR(r.response.achieved_angle_rad, M_PI / 2, 0.02);
  EXPECT_FALSE(r.response.collision);
  EXPECT_EQ(r.response.odom_pose.header.frame_id, "odom");
  EXPECT_GT(r.response.duration_s, 2.0);
  const auto f = forward(0.5);
  ASSERT_TRUE(f.response.success) << f.response.message;
  EXPECT_NEAR(f.response.achieved_distance_m, 0.5, 0.01);
  EXPECT_FALSE(f.response.collision);
  // odom agrees with the pose the service returned.
  ros::WallDuration(0.3).sleep();
  const auto o = g_odom->latest();
  EXPECT_NEAR(o.pose.pose.position.x, f.response.odom_pose.pose.position.x, 0.005);
  EXPECT_NEAR(o.pose.pose.position.y, f.response.odom_pose.pose.position.y, 0.005);
  const auto back = forward(-0.2);
  EXPECT_TRUE(back.response.success) << back.response.message;
  EXPECT_NEAR(back.response.achieved_distance_m, -0.2, 0.01);
  const auto far = forward(6.0);
  EXPECT_FALSE(far.response.success);
  EXPECT_NE(far.response.message.find("distance_m"), std::string::npos) << far.response.message;
}

TEST(PioneerDriver, C2_BadRequestsAreRefusedAndMoveNothing) {
  ros::WallDuration(0.5).sleep();
  const auto before = g_odom->latest();
  for (double a : {50.0, -7.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    const auto r = rotate(a);
    EXPECT_FALSE(r.response.success) << a;
    EXPECT_NE(r.response.message.find("angle_rad = "), std::string::npos) << r.response.message;
    EXPECT_NE(r.response.message.find("must be finite and within [-6.283, 6.283]"), std::string::npos)
        << r.response.message;
  }
  for (double d : {100.0, -5.5, std::nan(""), -std::numeric_limits<double>::infinity()}) {
    const auto f = forward(d);
    EXPECT_FALSE(f.response.success) << d;
    EXPECT_NE(f.response.message.find("distance_m = "), std::string::npos) << f.response.message;
    EXPECT_NE(f.response.message.find("must be finite and within [-5.000, 5.000]"), std::string::npos)
        << f.response.message;
  }
  ros::WallDuration(0.5).sleep();
  const auto after = g_odom->latest();
  EXPECT_EQ(after.pose.pose.position.x, before.pose.pose.position.x);
  EXPECT_EQ(after.pose.pose.position.y, before.pose.pose.position.y);
  EXPECT_EQ(after.pose.pose.orientation.z, before.pose.pose.orientation.z);
  EXPECT_EQ(after.twist.twist.linear.x, 0.0);
  EXPECT_EQ(after.twist.twist.angular.z, 0.0);
}

TEST(PioneerDriver, D_CmdVelTimeoutStopsTheRobot) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(5.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < end) ros::WallDuration(0.05).sleep();
  geometry_msgs::Twist twist;
  twist.linear.x = 0.2;
  for (int i = 0; i < 10; ++i) {
    pub.publish(twist);
    ros::WallDuration(0.1).sleep();
  }
  EXPECT_GT(g_odom->latest().twist.twist.linear.x, 0.05);
  // The client "crashes": no more commands. The driver stops the robot after 0.5 s.
  ros::WallDuration(2.0).sleep();
  EXPECT_NEAR(g_odom->latest().twist.twist.linear.x, 0.0, 1e-9);
  ros::WallDuration(1.1).sleep();
  EXPECT_GE(g_diag->number("cmd_vel timeouts"), 1.0);
}

TEST(PioneerDriver, E_CorruptChecksumsDroppedBytesAndGarbageAreSurvived) {
  inject("corrupt 5");
  inject("drop 5");
  inject("garbage 300");
  const auto f = forward(0.3);
  EXPECT_TRUE(f.response.success) << f.response.message;
  EXPECT_NEAR(f.response.achieved_distance_m, 0.3, 0.01);
  ros::WallDuration(1.1).sleep();
  EXPECT_GE(g_diag->number("checksum errors"), 5.0);
  EXPECT_GT(g_diag->number("skipped bytes"), 0.0);
  EXPECT_EQ(g_diag->value("link"), "connected");
}

TEST(PioneerDriver, F_StallAbortsTheMotion) {
  inject("stall on");
  const ros::WallTime t0 = ros::WallTime::now();
  const auto f = forward(1.0);
  EXPECT_FALSE(f.response.success);
  EXPECT_TRUE(f.response.collision);
  EXPECT_NE(f.response.message.find("stall"), std::string::npos) << f.response.message;
  EXPECT_LT((ros::WallTime::now() - t0).toSec(), 4.0);
  inject("stall off");
}

TEST(PioneerDriver, G_BumperAbortsForwardButAllowsBackingOff) {
  inject("bump front");
  const auto f = forward(0.5);
  EXPECT_FALSE(f.response.success);
  EXPECT_TRUE(f.response.collision);
  EXPECT_NE(f.response.message.find("front bumper"), std::string::npos) << f.response.message;
  const auto b = forward(-0.1);
  EXPECT_TRUE(b.response.success) << b.response.message;
  inject("bump off");
}

TEST(PioneerDriver, H_FrozenEncodersTimeOut) {
  inject("encoder on");
  const ros::WallTime t0 = ros::WallTime::now();
  const auto r = rotate(0.5);
  EXPECT_FALSE(r.response.success);
  EXPECT_FALSE(r.response.collision);
  EXPECT_NE(r.response.message.find("timeout"), std::string::npos) << r.response.message;
  EXPECT_LT((ros::WallTime::now() - t0).toSec(), 12.0);
  inject("encoder off");
}

TEST(PioneerDriver, H2_MotorPowerOffIsReportedAndReEnabled) {
  inject("motors off");
  const auto f = forward(0.3);
  EXPECT_FALSE(f.response.success);
  EXPECT_FALSE(f.response.collision);
  EXPECT_NE(f.response.message.find("motors disabled"), std::string::npos) << f.response.message;
  ros::WallDuration(1.1).sleep();
  EXPECT_EQ(g_diag->status.level, diagnostic_msgs::DiagnosticStatus::WARN) << g_diag->status.message;
  inject("motors on");  // the switch is back on; the driver sends ENABLE for the next motion
  const auto again = forward(0.2);
  EXPECT_TRUE(again.response.success) << again.response.message;
}

TEST(PioneerDriver, I_SilenceDuringAMotionIsReportedAndRecovered) {
  const double losses = g_diag->number("link losses");
  auto call = std::async(std::launch::async, [] { return forward(1.0); });
  ros::WallDuration(1.0).sleep();
  inject("silence 3");
  ASSERT_EQ(call.wait_for(std::chrono::seconds(6)), std::future_status::ready)
      << "forward hung after the robot fell silent";
  const auto f = call.get();
  EXPECT_FALSE(f.response.success);
  EXPECT_FALSE(f.response.collision);
  EXPECT_NE(f.response.message.find("link to the robot lost"), std::string::npos) << f.response.message;
  // While silent there is no odom; afterwards the driver reconnects (the session is still open).
  ASSERT_TRUE(odomFlows(5, 15.0)) << "odom did not resume after the silence";
  ros::WallDuration(1.1).sleep();
  EXPECT_GT(g_diag->number("link losses"), losses);
  const auto r = rotate(-0.3);
  EXPECT_TRUE(r.response.success) << r.response.message;
}

TEST(PioneerDriver, J_DisconnectIsReportedAndRecovered) {
  const double recoveries = g_diag->number("recoveries (session still open)");
  inject("disconnect 2");
  const auto f = forward(0.3);  // the link is down (or goes down during the motion)
  EXPECT_FALSE(f.response.success);
  EXPECT_TRUE(f.response.message.find("not connected") != std::string::npos ||
              f.response.message.find("link to the robot lost") != std::string::npos)
      << f.response.message;
  // Diagnostics (1 Hz) report the lost link while the port is gone (2 s).
  bool reported = false;
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(2.5);
  while (!reported && ros::WallTime::now() < end) {
    {
      std::lock_guard<std::mutex> lock(g_diag->mutex);
      reported = g_diag->status.level == diagnostic_msgs::DiagnosticStatus::ERROR &&
                 g_diag->status.message.find("not connected") != std::string::npos;
    }
    ros::WallDuration(0.05).sleep();
  }
  EXPECT_TRUE(reported) << "diagnostics did not report the lost link";
  ASSERT_TRUE(odomFlows(5, 15.0)) << "odom did not resume after the disconnect";
  // The robot kept its session open while the port was gone: the driver closed it and reconnected.
  ros::WallDuration(1.1).sleep();
  EXPECT_GT(g_diag->number("recoveries (session still open)"), recoveries);
  const auto again = forward(0.2);
  EXPECT_TRUE(again.response.success) << again.response.message;
}

TEST(PioneerDriver, K_OdomNeverCarriedGarbage) {
  std::lock_guard<std::mutex> lock(g_odom->mutex);
  EXPECT_GT(g_odom->count, 100);
  EXPECT_EQ(g_odom->bad, 0) << g_odom->first_problem;
  EXPECT_LT(g_odom->max_step, 0.05);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "pioneer_rostest");
  ros::NodeHandle nh;
  OdomWatch odom;
  DiagWatch diag;
  g_odom = &odom;
  g_diag = &diag;
  ros::Subscriber s1 = nh.subscribe("odom", 100, &OdomWatch::onOdom, &odom);
  ros::Subscriber s2 = nh.subscribe("/diagnostics", 10, &DiagWatch::onDiag, &diag);
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  return result;
}
