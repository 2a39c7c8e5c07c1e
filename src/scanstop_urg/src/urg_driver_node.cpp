#include "scanstop_urg/urg_driver_node.h"

#include <scanstop_msgs/Progress.h>

#include <utility>
#include <vector>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_common/ros/params.h"

namespace scanstop {
namespace urg {

DriverConfig readDriverConfig(ros_params::ParamReader& params) {
  const ros::NodeHandle& pnh = params.handle();
  DriverConfig c;
  params.optional("port", c.urg_port);
  params.optional("baud", c.urg_baud);
  params.optional("reply_timeout_s", c.urg.reply_timeout_s);
  params.optional("scan_timeout_s", c.urg.scan_timeout_s);
  params.optional("platform/port", c.platform_port);
  params.optional("platform/baud", c.platform_baud);
  params.optional("platform/reply_timeout_s", c.stepper.reply_timeout_s);
  params.optional("platform/home_timeout_s", c.stepper.home_timeout_s);
  params.optional("platform/retries", c.stepper.retries);
  std::string platform_type = "stepper";
  params.optional("platform/type", platform_type);
  if (platform_type != "stepper")
    throw ConfigError("parameter '" + pnh.resolveName("platform/type") + "' = '" + platform_type +
                      "': only 'stepper' is implemented");
  ScanGeometry& g = c.scanner.geometry;
  params.optional("scanner/height_m", g.height_m);
  params.optional("scanner/x_offset_m", g.x_offset_m);
  params.optional("scanner/mount_offset_m", g.mount_offset_m);
  params.optional("scanner/first_step", g.first_step);
  params.optional("scanner/last_step", g.last_step);
  params.optional("scanner/min_range_m", g.min_range_m);
  params.optional("scanner/max_range_m", g.max_range_m);
  c.urg.first_step = g.first_step;
  c.urg.last_step = g.last_step;
  params.optional("max_plane_retries", c.scanner.max_plane_retries);
  params.optional("max_consecutive_dropped", c.scanner.max_consecutive_dropped);
  params.optional("settle_time_s", c.scanner.settle_time_s);
  params.optional("outlier_filter", c.scanner.outlier_filter);
  params.optional("outlier_tolerance_abs_m", c.scanner.filter.tolerance_abs_m);
  params.optional("outlier_tolerance_rel", c.scanner.filter.tolerance_rel);
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(std::string("parameters of ") + pnh.getNamespace() + ": " + e.what());
  }
  return c;
}

StandstillConfig readStandstillConfig(ros_params::ParamReader& params) {
  const ros::NodeHandle& pnh = params.handle();
  StandstillConfig c;
  params.optional("standstill/max_linear_speed_mps", c.max_linear_speed_mps);
  params.optional("standstill/max_angular_speed_radps", c.max_angular_speed_radps);
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(std::string("parameters of ") + pnh.getNamespace() + ": " + e.what());
  }
  return c;
}

NodeParameters readNodeParameters(ros_params::ParamReader& params) {
  NodeParameters n;
  params.known({"master_timeout_s"});  // main()'s master watchdog
  params.optional("odom_topic", n.odom_topic);
  if (n.odom_topic.empty())
    throw ConfigError("parameter '" + params.resolve("odom_topic") + "' is empty: give the base's odometry topic");
  params.optional("reconnect_interval_s", n.reconnect_interval_s, 0.05, 600.0, "s");
  params.optional("diagnostic_period", n.diagnostic_period_s, 0.05, 600.0, "s");
  params.optional("odom_timeout_s", n.odom_timeout_s, 0.0, 60.0, "s");
  params.optional("require_odom", n.require_odom);
  params.optional("base_frame", n.base_frame);
  params.optional("laser_frame", n.laser_frame);
  params.optional("odom_frame", n.odom_frame);
  params.frames({{"base_frame", n.base_frame}, {"laser_frame", n.laser_frame}, {"odom_frame", n.odom_frame}});
  return n;
}

UrgDriverNode::UrgDriverNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
    : tf_listener_(tf_buffer_), diagnostics_(nh, pnh) {
  ros_params::ParamReader params(pnh, "rotating_urg_driver");
  const DriverConfig config = readDriverConfig(params);
  standstill_ = readStandstillConfig(params);
  const NodeParameters node = readNodeParameters(params);
  params.rejectUnknown();
  odom_timeout_s_ = node.odom_timeout_s;
  require_odom_ = node.require_odom;
  base_frame_ = node.base_frame;
  laser_frame_ = node.laser_frame;
  odom_frame_ = node.odom_frame;
  driver_ = std::make_unique<UrgDriver>(config);

  Eigen::Isometry3d T_base_laser = Eigen::Isometry3d::Identity();
  T_base_laser.translation() =
      Eigen::Vector3d(config.scanner.geometry.x_offset_m, 0.0, config.scanner.geometry.height_m);
  static_tf_.sendTransform(ros_conv::toTransformMsg(T_base_laser, base_frame_, laser_frame_, ros::Time::now()));

  diagnostics_.setHardwareID("URG-04LX on " + config.urg_port + ", platform on " + config.platform_port);
  diagnostics_.add("rotating URG", this, &UrgDriverNode::diagnose);

  scan_pub_ = nh.advertise<sensor_msgs::PointCloud2>("scanner/last_scan", 1, true);
  progress_pub_ = nh.advertise<scanstop_msgs::Progress>("scanner/progress", 10);
  odom_sub_ = nh.subscribe(node.odom_topic, 20, &UrgDriverNode::onOdom, this);
  take_scan_srv_ = nh.advertiseService("scanner/take_scan", &UrgDriverNode::onTakeScan, this);
  reconnect_timer_ =
      nh.createWallTimer(ros::WallDuration(node.reconnect_interval_s), &UrgDriverNode::onReconnectTimer, this);
  diagnostics_timer_ =
      nh.createWallTimer(ros::WallDuration(node.diagnostic_period_s), &UrgDriverNode::onDiagnosticsTimer, this);
  ROS_INFO("rotating_urg_driver: URG on %s, platform on %s; connecting", config.urg_port.c_str(),
           config.platform_port.c_str());
}

void UrgDriverNode::onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
  const std::string problem = baseMotionProblem(msg->twist.twist.linear.x, msg->twist.twist.angular.z, standstill_);
  std::lock_guard<std::mutex> lock(odom_mutex_);
  base_motion_ = problem;
  if (scanning_ && !problem.empty() && moved_during_scan_.empty()) moved_during_scan_ = problem;
}

void UrgDriverNode::onReconnectTimer(const ros::WallTimerEvent&) {
  std::unique_lock<std::mutex> lock(device_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // a scan is running
  const bool ok = driver_->connected() ? driver_->checkLink() || driver_->connect() : driver_->connect();
  if (ok != was_connected_) {
    const DriverStats s = driver_->stats();
    if (ok)
      ROS_INFO("rotating_urg_driver: %s", s.state.c_str());
    else
      ROS_WARN("rotating_urg_driver: %s", s.state.c_str());
  }
  was_connected_ = ok;
}

void UrgDriverNode::onDiagnosticsTimer(const ros::WallTimerEvent&) { diagnostics_.force_update(); }

void UrgDriverNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const DriverStats s = driver_->stats();
  if (s.connected)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, s.state);
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, s.state);
  status.add("connected", s.connected);
  status.add("connects", s.connects);
  status.add("connection losses", s.connection_losses);
  status.add("scans", s.scans_ok);
  status.add("failed scans", s.scans_failed);
  status.add("checksum errors", s.checksum_errors);
  status.add("malformed replies", s.format_errors);
  status.add("timeouts", s.timeouts);
  status.add("skipped lines", s.skipped_lines);
  status.add("SCIP 1.1 switches", s.scip11_switches);
  status.add("plane re-reads", s.plane_retries);
  status.add("dropped planes", s.planes_dropped);
  status.add("outliers removed", s.outliers_removed);
  status.add("outlier share (last scan)", s.last_outlier_share);
  status.add("outlier share (all scans)",
             s.points_before_filter ? static_cast<double>(s.outliers_removed) / s.points_before_filter : 0.0);
  status.add("last error", s.last_error);
  std::lock_guard<std::mutex> lock(odom_mutex_);
  status.add("base", base_motion_.empty() ? std::string("standing still (or no odom)") : base_motion_);
}

bool UrgDriverNode::odomPose(geometry_msgs::PoseStamped* pose, std::string* error) {
  try {
    const geometry_msgs::TransformStamped T =
        tf_buffer_.lookupTransform(odom_frame_, base_frame_, ros::Time(0), ros::Duration(odom_timeout_s_));
    pose->header = T.header;
    pose->pose.position.x = T.transform.translation.x;
    pose->pose.position.y = T.transform.translation.y;
    pose->pose.position.z = T.transform.translation.z;
    pose->pose.orientation = T.transform.rotation;
    return true;
  } catch (const tf2::TransformException& e) {
    *error = e.what();
    return false;
  }
}

bool UrgDriverNode::onTakeScan(scanstop_msgs::TakeScan::Request& req, scanstop_msgs::TakeScan::Response& res) {
  res.success = false;
  res.message = checkScanPlanes(req.planes);
  if (!res.message.empty()) return true;
  std::lock_guard<std::mutex> lock(device_mutex_);
  {
    // Refused while the base moves (the last odom twist); a motion during the scan discards it.
    std::lock_guard<std::mutex> odom_lock(odom_mutex_);
    if (!base_motion_.empty()) {
      res.message = base_motion_;
      ROS_WARN("rotating_urg_driver: scan refused: %s", res.message.c_str());
      return true;
    }
    scanning_ = true;
    moved_during_scan_.clear();
  }
  struct ScanningFlag {
    UrgDriverNode* node;
    ~ScanningFlag() {
      std::lock_guard<std::mutex> odom_lock(node->odom_mutex_);
      node->scanning_ = false;
    }
  } scanning_flag{this};
  // The robot stands still during the scan: its odometry pose now is the pose of the scan.
  std::string tf_error;
  if (!odomPose(&res.odom_pose, &tf_error)) {
    if (require_odom_) {
      res.success = false;
      res.message = "no odometry pose (" + odom_frame_ + " -> " + base_frame_ + " not in tf within " +
                    std::to_string(odom_timeout_s_) + " s: " + tf_error + "); is the base driver running?";
      return true;
    }
    res.odom_pose = geometry_msgs::PoseStamped();
    res.odom_pose.header.frame_id = odom_frame_;
    res.odom_pose.header.stamp = ros::Time::now();
    res.odom_pose.pose.orientation.w = 1.0;
  }
  scanstop_msgs::Progress progress;
  progress.header.stamp = ros::Time::now();
  progress.step = "take_scan";
  progress.total = req.planes;
  progress.message = "scanning " + std::to_string(req.planes) + " planes";
  progress_pub_.publish(progress);
  const ScanResult scan = driver_->takeScan(req.planes, [&](int done, int total) {
    if (done % 10 != 0 && done != total) return;
    progress.header.stamp = ros::Time::now();
    progress.done = static_cast<uint32_t>(done);
    progress.message = "plane " + std::to_string(done) + " of " + std::to_string(total);
    progress_pub_.publish(progress);
  });
  was_connected_ = driver_->connected();
  res.duration_s = scan.duration_s;
  res.counts.raw_points = scan.raw_points;
  res.counts.valid_points = scan.valid_points;
  res.counts.planes_dropped = scan.planes_dropped;
  res.counts.outliers_removed = scan.outliers_removed;
  res.success = scan.success;
  res.message = scan.message;
  {
    std::lock_guard<std::mutex> odom_lock(odom_mutex_);
    if (res.success && !moved_during_scan_.empty()) {
      res.success = false;
      res.message = "the scan is discarded: the base moved during it (" + moved_during_scan_ + ")";
    }
  }
  progress.header.stamp = ros::Time::now();
  progress.message = res.message;
  progress_pub_.publish(progress);
  if (!res.success) {
    ROS_WARN("rotating_urg_driver: scan failed: %s", res.message.c_str());
    return true;  // no cloud: a failed scan is never published
  }
  res.cloud = ros_conv::toMsg(scan.cloud, base_frame_, ros::Time::now());
  scan_pub_.publish(res.cloud);
  ROS_INFO("rotating_urg_driver: %s in %.1f s", scan.message.c_str(), scan.duration_s);
  return true;
}

}  // namespace urg
}  // namespace scanstop
