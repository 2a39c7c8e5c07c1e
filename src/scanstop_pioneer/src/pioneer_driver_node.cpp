#include "scanstop_pioneer/pioneer_driver_node.h"

#include <nav_msgs/Odometry.h>
#include <sensor_msgs/BatteryState.h>
#include <std_msgs/Bool.h>

#include <cmath>

#include "scanstop_common/error.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"

namespace scanstop {
namespace pioneer {
namespace {}  // namespace

PioneerDriverNode::Parameters PioneerDriverNode::readParameters(ros_params::ParamReader& params) {
  Parameters p;
  DriverConfig& c = p.driver;
  const auto opt = [&params](const std::string& name, auto& value) { params.optional(name, value); };
  params.known({"master_timeout_s", "diagnostic_period"});  // main()'s watchdog; diagnostic_updater's
  c.port = params.require<std::string>("port");
  opt("baud", c.baud);
  RobotParams& r = c.robot;
  opt("robot/subclass", r.subclass);
  opt("robot/angle_conv_rad", r.angle_conv_rad);
  opt("robot/dist_conv_mm", r.dist_conv_mm);
  opt("robot/vel_conv", r.vel_conv);
  opt("robot/range_conv_mm", r.range_conv_mm);
  opt("robot/diff_conv", r.diff_conv);
  opt("robot/max_velocity_mps", r.max_velocity_mps);
  opt("robot/max_rot_velocity_radps", r.max_rot_velocity_radps);
  opt("reply_timeout_s", c.client.reply_timeout_s);
  opt("sync_attempts", c.client.sync_attempts);
  opt("close_wait_s", c.client.close_wait_s);
  opt("sip_timeout_s", c.sip_timeout_s);
  opt("reconnect_period_s", c.reconnect_period_s);
  opt("pulse_period_s", c.pulse_period_s);
  opt("cmd_vel_timeout_s", c.cmd_vel_timeout_s);
  opt("max_linear_speed_mps", c.max_linear_speed_mps);
  opt("max_angular_speed_radps", c.max_angular_speed_radps);
  MotionConfig& m = c.motion;
  opt("motion/linear_speed_mps", m.linear_speed_mps);
  opt("motion/angular_speed_radps", m.angular_speed_radps);
  opt("motion/min_linear_speed_mps", m.min_linear_speed_mps);
  opt("motion/min_angular_speed_radps", m.min_angular_speed_radps);
  opt("motion/linear_decel_mps2", m.linear_decel_mps2);
  opt("motion/angular_decel_radps2", m.angular_decel_radps2);
  opt("motion/approach_distance_m", m.approach_distance_m);
  opt("motion/approach_angle_rad", m.approach_angle_rad);
  opt("motion/distance_tolerance_m", m.distance_tolerance_m);
  opt("motion/angle_tolerance_rad", m.angle_tolerance_rad);
  opt("motion/timeout_factor", m.timeout_factor);
  opt("motion/timeout_extra_s", m.timeout_extra_s);
  opt("motion/stall_time_s", m.stall_time_s);
  opt("motion/motors_disabled_time_s", m.motors_disabled_time_s);
  opt("motion/settle_timeout_s", m.settle_timeout_s);
  opt("motion/max_forward_m", m.max_forward_m);
  opt("motion/max_rotate_rad", m.max_rotate_rad);
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(std::string(e.what()) + " (private namespace " + params.handle().getNamespace() + ")");
  }
  opt("odom_frame", p.odom_frame);
  opt("base_frame", p.base_frame);
  opt("publish_tf", p.publish_tf);
  params.frames({{"odom_frame", p.odom_frame}, {"base_frame", p.base_frame}});
  return p;
}

PioneerDriverNode::PioneerDriverNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : updater_(nh, pnh) {
  ros_params::ParamReader params(pnh, "pioneer_driver");
  const Parameters parameters = readParameters(params);
  params.rejectUnknown();
  const DriverConfig& config = parameters.driver;
  odom_frame_ = parameters.odom_frame;
  base_frame_ = parameters.base_frame;
  publish_tf_ = parameters.publish_tf;

  odom_pub_ = nh.advertise<nav_msgs::Odometry>("odom", 20);
  battery_pub_ = nh.advertise<sensor_msgs::BatteryState>("battery", 5);
  stall_pub_ = nh.advertise<std_msgs::Bool>("base/stall", 5, true);
  bumper_pub_ = nh.advertise<std_msgs::Bool>("base/bumper", 5, true);

  driver_ = std::make_unique<PioneerDriver>(config);
  driver_->setLogCallback([](int level, const std::string& text) {
    if (level == 0)
      ROS_INFO("pioneer_driver: %s", text.c_str());
    else if (level == 1)
      ROS_WARN("pioneer_driver: %s", text.c_str());
    else
      ROS_ERROR("pioneer_driver: %s", text.c_str());
  });
  driver_->setSipCallback([this](const DriverStatus& s) { onSip(s); });

  updater_.setHardwareID("pioneer@" + config.port);
  updater_.add("Pioneer base", this, &PioneerDriverNode::diagnose);
  cmd_vel_sub_ = nh.subscribe("cmd_vel", 5, &PioneerDriverNode::onCmdVel, this);
  rotate_srv_ = nh.advertiseService("base/rotate", &PioneerDriverNode::onRotate, this);
  forward_srv_ = nh.advertiseService("base/forward", &PioneerDriverNode::onForward, this);
  timer_ = nh.createWallTimer(ros::WallDuration(1.0), &PioneerDriverNode::onTimer, this);
  ROS_INFO("pioneer_driver: port %s at %d baud, robot subclass %s", config.port.c_str(), config.baud,
           config.robot.subclass.c_str());
  driver_->start();
}

void PioneerDriverNode::onMasterLost(const std::string& why) {
  ROS_ERROR("pioneer_driver: stopping the robot and refusing motions until the ROS master is back");
  driver_->halt(why);
}

void PioneerDriverNode::onMasterBack() {
  ROS_WARN("pioneer_driver: the ROS master is back: motions accepted again");
  driver_->allowMotion();
}

PioneerDriverNode::~PioneerDriverNode() {
  if (driver_) driver_->stop();
}

void PioneerDriverNode::onSip(const DriverStatus& s) {
  if (!s.odom.isFinite() || !std::isfinite(s.v_mps) || !std::isfinite(s.w_radps)) return;
  const ros::Time stamp = ros::Time::now();
  nav_msgs::Odometry odom;
  odom.header.stamp = stamp;
  odom.header.frame_id = odom_frame_;
  odom.child_frame_id = base_frame_;
  odom.pose.pose = ros_conv::toPoseMsg(s.odom);
  odom.twist.twist.linear.x = s.v_mps;
  odom.twist.twist.angular.z = s.w_radps;
  odom_pub_.publish(odom);
  if (publish_tf_) tf_.sendTransform(ros_conv::toTransformMsg(s.odom, odom_frame_, base_frame_, stamp));
  std_msgs::Bool stall, bumper;
  stall.data = s.sip.stalled();
  bumper.data = s.sip.frontBumpers() != 0 || s.sip.rearBumpers() != 0;
  stall_pub_.publish(stall);
  bumper_pub_.publish(bumper);
}

void PioneerDriverNode::onTimer(const ros::WallTimerEvent&) {
  const DriverStatus s = driver_->status();
  const ros::WallTime now = ros::WallTime::now();
  if (!rate_time_.isZero() && now > rate_time_)
    sip_rate_hz_ = static_cast<double>(s.sips - rate_sips_) / (now - rate_time_).toSec();
  rate_sips_ = s.sips;
  rate_time_ = now;
  updater_.force_update();
  if (s.link != LinkState::kConnected || !s.have_sip) return;
  sensor_msgs::BatteryState battery;
  battery.header.stamp = ros::Time::now();
  battery.header.frame_id = base_frame_;
  battery.voltage = static_cast<float>(s.sip.batteryVolts());
  battery.current = battery.charge = battery.capacity = battery.design_capacity = battery.percentage = NAN;
  battery.power_supply_status = sensor_msgs::BatteryState::POWER_SUPPLY_STATUS_UNKNOWN;
  battery.power_supply_health = sensor_msgs::BatteryState::POWER_SUPPLY_HEALTH_UNKNOWN;
  battery.power_supply_technology = sensor_msgs::BatteryState::POWER_SUPPLY_TECHNOLOGY_UNKNOWN;
  battery.present = true;
  battery_pub_.publish(battery);
}

void PioneerDriverNode::onCmdVel(const geometry_msgs::Twist::ConstPtr& msg) {
  std::string reason;
  if (!driver_->commandVelocity(msg->linear.x, msg->angular.z, &reason))
    ROS_WARN_THROTTLE(2.0, "pioneer_driver: cmd_vel ignored: %s", reason.c_str());
}

bool PioneerDriverNode::onRotate(scanstop_msgs::Rotate::Request& req, scanstop_msgs::Rotate::Response& res) {
  const MotionResult r = driver_->rotate(req.angle_rad);
  res.success = r.success;
  res.message = r.message;
  res.duration_s = r.duration_s;
  res.achieved_angle_rad = r.achieved;
  res.collision = r.collision;
  res.odom_pose = ros_conv::toPoseStamped(r.odom, odom_frame_, ros::Time::now());
  if (!r.success) ROS_WARN("pioneer_driver: rotate %.3f rad failed: %s", req.angle_rad, r.message.c_str());
  return true;
}

bool PioneerDriverNode::onForward(scanstop_msgs::Forward::Request& req, scanstop_msgs::Forward::Response& res) {
  const MotionResult r = driver_->forward(req.distance_m);
  res.success = r.success;
  res.message = r.message;
  res.duration_s = r.duration_s;
  res.achieved_distance_m = r.achieved;
  res.collision = r.collision;
  res.odom_pose = ros_conv::toPoseStamped(r.odom, odom_frame_, ros::Time::now());
  if (!r.success) ROS_WARN("pioneer_driver: forward %.3f m failed: %s", req.distance_m, r.message.c_str());
  return true;
}

void PioneerDriverNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const DriverStatus s = driver_->status();
  using diagnostic_msgs::DiagnosticStatus;
  if (s.link != LinkState::kConnected) {
    stat.summary(DiagnosticStatus::ERROR, "not connected: " + (s.last_error.empty() ? "connecting" : s.last_error));
  } else if (!s.have_sip) {
    stat.summary(DiagnosticStatus::WARN, "connected, waiting for the first SIP");
  } else if (sip_rate_hz_ < 5.0) {
    stat.summary(DiagnosticStatus::WARN, "SIPs arrive slowly (" + std::to_string(sip_rate_hz_) + " Hz, expected 10)");
  } else if (s.sip.stalled() || s.sip.frontBumpers() || s.sip.rearBumpers()) {
    stat.summary(DiagnosticStatus::WARN, s.sip.stalled() ? "wheel stall" : "bumper pressed");
  } else if (!s.sip.motorsEnabled()) {
    stat.summary(DiagnosticStatus::WARN, "motors disabled");
  } else {
    stat.summary(DiagnosticStatus::OK, "connected");
  }
  stat.add("port", s.port);
  stat.add("link", s.link == LinkState::kConnected ? "connected" : "disconnected");
  stat.add("robot", s.robot.name + " (" + s.robot.robot_class + " " + s.robot.subclass + ")");
  stat.add("last error", s.last_error);
  stat.add("last connect", s.connect_note);
  stat.add("connects", s.connects);
  stat.add("recoveries (session still open)", s.recoveries);
  stat.add("link losses", s.link_losses);
  stat.add("SIPs", s.sips);
  stat.addf("SIP rate [Hz]", "%.1f", sip_rate_hz_);
  stat.add("checksum errors", s.checksum_errors);
  stat.add("bad count bytes", s.bad_counts);
  stat.add("skipped bytes", s.skipped_bytes);
  stat.add("SIP decode errors", s.sip_decode_errors);
  stat.add("cmd_vel timeouts", s.cmd_vel_timeouts);
  stat.add("motion active", s.motion_active);
  if (s.have_sip) {
    stat.add("battery [V]", s.sip.batteryVolts());
    stat.add("motors enabled", s.sip.motorsEnabled());
    stat.add("left wheel stall", s.sip.leftStall());
    stat.add("right wheel stall", s.sip.rightStall());
    stat.addf("front bumpers", "0x%02X", s.sip.frontBumpers());
    stat.addf("rear bumpers", "0x%02X", s.sip.rearBumpers());
  }
}

}  // namespace pioneer
}  // namespace scanstop
