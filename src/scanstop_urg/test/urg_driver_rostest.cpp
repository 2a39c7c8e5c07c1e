// rostest of rotating_urg_driver against urg_emulator: the take_scan contract (layout, fields,
// frames, odometry pose, counts, last_scan, tf, diagnostics), then every fault the emulator can
// inject. After each fault the node either recovers (the scan succeeds and every finite point
// equals the clean scan's point: nothing garbled is published) or fails the scan with a clear
// message, reports it in diagnostics and reconnects by itself; no call hangs.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <scanstop_msgs/Progress.h>
#include <scanstop_msgs/TakeScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <future>
#include <map>
#include <mutex>

#include "scanstop_common/error.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_urg/urg_driver_node.h"

namespace {

using scanstop::PointCloud;
namespace ros_conv = scanstop::ros_conv;

std::string g_control;
PointCloud g_clean;
std::mutex g_mutex;
std::map<std::string, std::string> g_diag;
int g_diag_level = -1;
std::atomic<int> g_last_scan_msgs{0};

void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
  for (const auto& s : msg->status) {
    if (s.name.find("rotating URG") == std::string::npos) continue;
    std::lock_guard<std::mutex> lock(g_mutex);
    g_diag.clear();
    for (const auto& kv : s.values) g_diag[kv.key] = kv.value;
    g_diag["message"] = s.message;
    g_diag_level = s.level;
  }
}

void onLastScan(const sensor_msgs::PointCloud2::ConstPtr&) { ++g_last_scan_msgs; }

std::string diag(const std::string& key) {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_diag.count(key) ? g_diag[key] : "";
}

/// Waits (wall time) until diagnostics say connected == `connected`.
bool waitConnected(bool connected, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < end) {
    if (diag("connected") == (connected ? "True" : "False")) return true;
    ros::WallDuration(0.05).sleep();
  }
  return false;
}

void inject(const std::string& command) {
  const int fd = ::open(g_control.c_str(), O_WRONLY | O_NONBLOCK);
  ASSERT_GE(fd, 0) << "cannot open the emulator's control FIFO " << g_control;
  const std::string line = command + "\n";
  ASSERT_EQ(::write(fd, line.data(), line.size()), static_cast<ssize_t>(line.size()));
  ::close(fd);
  ros::WallDuration(0.3).sleep();  // let the emulator take it
}

scanstop_msgs::TakeScan scan(uint16_t planes = 50, double max_s = 60.0) {
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::TakeScan>("scanner/take_scan");
  EXPECT_TRUE(client.waitForExistence(ros::Duration(30.0)));
  scanstop_msgs::TakeScan srv;
  srv.request.planes = planes;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(client.call(srv));
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(took, max_s) << "take_scan took " << took << " s";
  return srv;
}

/// Every finite point equals the clean scan's; dropped planes are all NaN. Returns the number of
/// points that are valid in the clean scan but not here.
size_t checkAgainstClean(const scanstop_msgs::TakeScan& srv) {
  const PointCloud c = ros_conv::fromMsg(srv.response.cloud);
  EXPECT_EQ(c.width, g_clean.width);
  EXPECT_EQ(c.height, g_clean.height);
  if (c.size() != g_clean.size()) return 0;
  size_t missing = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (c.points[i].allFinite()) {
      EXPECT_TRUE(g_clean.points[i].allFinite() && c.points[i] == g_clean.points[i]) << "point " << i << " garbled";
      if (!(g_clean.points[i].allFinite() && c.points[i] == g_clean.points[i])) return missing;
    } else if (g_clean.points[i].allFinite()) {
      ++missing;
    }
  }
  EXPECT_EQ(c.countFinite(), srv.response.counts.valid_points);
  return missing;
}

TEST(RotatingUrgDriver, CleanScanContract) {
  ASSERT_TRUE(waitConnected(true, 30.0)) << "never connected: " << diag("message");
  const int before = g_last_scan_msgs;
  const scanstop_msgs::TakeScan srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  const auto& cloud = srv.response.cloud;
  EXPECT_EQ(cloud.header.frame_id, "base_link");
  EXPECT_EQ(cloud.height, 50u);
  EXPECT_EQ(cloud.width, 682u);
  EXPECT_FALSE(cloud.is_dense);
  std::vector<std::string> names;
  for (const auto& f : cloud.fields) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"x", "y", "z", "range", "plane", "beam"}));
  EXPECT_EQ(srv.response.counts.raw_points, 50u * 682u);
  EXPECT_EQ(srv.response.counts.planes_dropped, 0u);
  EXPECT_GT(srv.response.counts.valid_points, 30000u);
  EXPECT_GT(srv.response.duration_s, 0.0);
  // The odometry pose comes from tf (odom -> base_link, broadcast by this test).
  EXPECT_EQ(srv.response.odom_pose.header.frame_id, "odom");
  EXPECT_NEAR(srv.response.odom_pose.pose.position.x, 1.5, 1e-9);
  EXPECT_NEAR(srv.response.odom_pose.pose.position.y, -0.5, 1e-9);
  g_clean = ros_conv::fromMsg(cloud);
  EXPECT_EQ(g_clean.countFinite(), srv.response.counts.valid_points);
  // The same cloud on scanner/last_scan.
  const auto last = ros::topic::waitForMessage<sensor_msgs::PointCloud2>("scanner/last_scan", ros::Duration(5.0));
  ASSERT_TRUE(last != nullptr);
  EXPECT_EQ(last->data, cloud.data);
  EXPECT_GT(g_last_scan_msgs, before);
  // Static tf base_link -> laser at the scanner height from config/urg.yaml.
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  const auto T = buffer.lookupTransform("base_link", "laser", ros::Time(0), ros::Duration(5.0));
  EXPECT_NEAR(T.transform.translation.z, 0.45, 1e-9);
  // Diagnostics.
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(diag("scans"), "1");
  EXPECT_EQ(diag("dropped planes"), "0");
  EXPECT_EQ(diag("SCIP 1.1 switches"), "1");  // the emulator boots in SCIP 1.1
  EXPECT_EQ(g_diag_level, 0);
  EXPECT_NE(diag("message").find("URG-04LX"), std::string::npos) << diag("message");
  EXPECT_FALSE(diag("outlier share (last scan)").empty());
}

TEST(RotatingUrgDriver, BadPlaneCountIsRefused) {
  const scanstop_msgs::TakeScan srv = scan(7);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("50, 100, 200, 400"), std::string::npos) << srv.response.message;
}

TEST(RotatingUrgDriver, TransmissionFaultsAreReRead) {
  ASSERT_FALSE(g_clean.empty());
  for (const std::string fault : {"corrupt 3", "drop 3 2", "truncate 2", "garbage", "powercycle"}) {
    SCOPED_TRACE(fault);
    const int msgs = g_last_scan_msgs;
    inject(fault);
    const scanstop_msgs::TakeScan srv = scan(50);
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    EXPECT_EQ(srv.response.counts.planes_dropped, 0u);
    EXPECT_EQ(checkAgainstClean(srv), 0u);
    ros::WallDuration(0.3).sleep();
    EXPECT_EQ(g_last_scan_msgs, msgs + 1);
  }
  ros::WallDuration(0.5).sleep();
  EXPECT_GE(std::stoi(diag("checksum errors")), 3);
  EXPECT_GE(std::stoi(diag("SCIP 1.1 switches")), 2);
  EXPECT_GE(std::stoi(diag("plane re-reads")), 5);
}

TEST(RotatingUrgDriver, PlatformStallFailsClearlyWithoutPublishing) {
  const int msgs = g_last_scan_msgs;
  inject("stall 1");
  const scanstop_msgs::TakeScan bad = scan(50);
  EXPECT_FALSE(bad.response.success);
  EXPECT_NE(bad.response.message.find("stall"), std::string::npos) << bad.response.message;
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(g_last_scan_msgs, msgs);
  const scanstop_msgs::TakeScan good = scan(50);
  ASSERT_TRUE(good.response.success) << good.response.message;
  EXPECT_EQ(checkAgainstClean(good), 0u);
}

TEST(RotatingUrgDriver, ShortSilenceDropsPlanesLongSilenceReconnects) {
  inject("silence 2");
  scanstop_msgs::TakeScan srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_GE(srv.response.counts.planes_dropped, 1u);
  EXPECT_LE(srv.response.counts.planes_dropped, 2u);
  EXPECT_GE(checkAgainstClean(srv), 1u);
  ros::WallDuration(0.5).sleep();
  EXPECT_GE(std::stoi(diag("dropped planes")), 1);
  // A long silence: the scan fails clearly and the driver reconnects when the URG is back.
  const int msgs = g_last_scan_msgs;
  inject("silence 6");
  srv = scan(50);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("stopped answering"), std::string::npos) << srv.response.message;
  EXPECT_TRUE(waitConnected(false, 5.0));
  EXPECT_EQ(g_diag_level, 2);
  EXPECT_TRUE(waitConnected(true, 30.0)) << diag("message");
  srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(checkAgainstClean(srv), 0u);
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(g_last_scan_msgs, msgs + 1);
}

TEST(RotatingUrgDriver, DisconnectIsNoticedReportedAndReconnected) {
  const int losses = std::stoi(diag("connection losses"));
  inject("disconnect 3");
  ASSERT_TRUE(waitConnected(false, 5.0)) << "the hang-up was not noticed";
  // The loss ("... hung up") or, once the emulator's pty is gone, the failing reconnect.
  const std::string m = diag("message");
  EXPECT_TRUE(m.find("hung up") != std::string::npos || m.find("cannot open") != std::string::npos) << m;
  scanstop_msgs::TakeScan srv = scan(50);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("not connected"), std::string::npos) << srv.response.message;
  ASSERT_TRUE(waitConnected(true, 30.0)) << diag("message");
  EXPECT_EQ(std::stoi(diag("connection losses")), losses + 1);
  srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(checkAgainstClean(srv), 0u);
}

TEST(RotatingUrgDriver, LaserFaultIsReportedUntilRepaired) {
  inject("laser_fault 1");
  inject("powercycle");  // the sensor restarts in SCIP 1.1 and its laser does not come on
  scanstop_msgs::TakeScan srv = scan(50);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("laser fault"), std::string::npos) << srv.response.message;
  ASSERT_TRUE(waitConnected(false, 5.0));
  ros::WallDuration(1.0).sleep();  // reconnect attempts keep failing, with the reason
  EXPECT_NE(diag("message").find("laser fault"), std::string::npos) << diag("message");
  EXPECT_EQ(diag("connected"), "False");
  inject("laser_fault 0");
  ASSERT_TRUE(waitConnected(true, 30.0)) << diag("message");
  srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(checkAgainstClean(srv), 0u);
}

TEST(RotatingUrgDriver, ShippedConfigEqualsTheDefaultsAndBadValuesAreNamed) {
  // config/urg.yaml, loaded unmodified into /urg_yaml by the launch file.
  scanstop::ros_params::ParamReader params(ros::NodeHandle("/urg_yaml"), "rotating_urg_driver");
  const scanstop::urg::DriverConfig c = scanstop::urg::readDriverConfig(params);
  const scanstop::urg::DriverConfig d;
  EXPECT_EQ(c.urg_port, d.urg_port);
  EXPECT_EQ(c.urg_baud, d.urg_baud);
  EXPECT_EQ(c.platform_port, d.platform_port);
  EXPECT_EQ(c.platform_baud, d.platform_baud);
  EXPECT_EQ(c.urg.reply_timeout_s, d.urg.reply_timeout_s);
  EXPECT_EQ(c.urg.scan_timeout_s, d.urg.scan_timeout_s);
  EXPECT_EQ(c.stepper.reply_timeout_s, d.stepper.reply_timeout_s);
  EXPECT_EQ(c.stepper.home_timeout_s, d.stepper.home_timeout_s);
  EXPECT_EQ(c.stepper.retries, d.stepper.retries);
  const auto &g = c.scanner.geometry, &dg = d.scanner.geometry;
  EXPECT_EQ(g.height_m, dg.height_m);
  EXPECT_EQ(g.x_offset_m, dg.x_offset_m);
  EXPECT_EQ(g.mount_offset_m, dg.mount_offset_m);
  EXPECT_EQ(g.first_step, dg.first_step);
  EXPECT_EQ(g.last_step, dg.last_step);
  EXPECT_EQ(g.min_range_m, dg.min_range_m);
  EXPECT_EQ(g.max_range_m, dg.max_range_m);
  EXPECT_EQ(c.scanner.max_plane_retries, d.scanner.max_plane_retries);
  EXPECT_EQ(c.scanner.max_consecutive_dropped, d.scanner.max_consecutive_dropped);
  EXPECT_EQ(c.scanner.settle_time_s, d.scanner.settle_time_s);
  EXPECT_EQ(c.scanner.outlier_filter, d.scanner.outlier_filter);
  EXPECT_EQ(c.scanner.filter.tolerance_abs_m, d.scanner.filter.tolerance_abs_m);
  EXPECT_EQ(c.scanner.filter.tolerance_rel, d.scanner.filter.tolerance_rel);
  const scanstop::urg::StandstillConfig st = scanstop::urg::readStandstillConfig(params), dst;
  EXPECT_EQ(st.max_linear_speed_mps, dst.max_linear_speed_mps);
  EXPECT_EQ(st.max_angular_speed_radps, dst.max_angular_speed_radps);
  const scanstop::urg::NodeParameters n = scanstop::urg::readNodeParameters(params), dn;
  EXPECT_EQ(n.odom_topic, dn.odom_topic);
  EXPECT_EQ(n.reconnect_interval_s, dn.reconnect_interval_s);
  EXPECT_EQ(n.diagnostic_period_s, dn.diagnostic_period_s);
  EXPECT_EQ(n.odom_timeout_s, dn.odom_timeout_s);
  EXPECT_EQ(n.require_odom, dn.require_odom);
  EXPECT_EQ(n.base_frame + n.laser_frame + n.odom_frame, dn.base_frame + dn.laser_frame + dn.odom_frame);
  // Every key of config/urg.yaml is one the node reads.
  EXPECT_TRUE(params.unknown().empty()) << params.unknown().front();
  ros::NodeHandle bad("/urg_bad");
  bad.setParam("scanner/height_m", 7.0);
  try {
    scanstop::ros_params::ParamReader bad_params(bad, "rotating_urg_driver");
    scanstop::urg::readDriverConfig(bad_params);
    ADD_FAILURE() << "accepted scanner/height = 7";
  } catch (const scanstop::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("scanner/height"), std::string::npos) << e.what();
  }
  bad.setParam("scanner/height_m", "high");
  try {
    scanstop::ros_params::ParamReader bad_params(bad, "rotating_urg_driver");
    scanstop::urg::readDriverConfig(bad_params);
    ADD_FAILURE() << "accepted a string height";
  } catch (const scanstop::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/urg_bad/scanner/height_m"), std::string::npos) << e.what();
  }
}

/// Publishes base odometry with a twist (the base driver's odom topic).
void publishTwist(ros::Publisher& pub, double v, double w) {
  nav_msgs::Odometry odom;
  odom.header.stamp = ros::Time::now();
  odom.header.frame_id = "odom";
  odom.child_frame_id = "base_link";
  odom.pose.pose.orientation.w = 1.0;
  odom.twist.twist.linear.x = v;
  odom.twist.twist.angular.z = w;
  pub.publish(odom);
  ros::WallDuration(0.3).sleep();  // let the driver receive it
}

TEST(RotatingUrgDriver, ScanIsRefusedWhileTheBaseMovesAndDiscardedWhenItMovedDuringTheScan) {
  ASSERT_TRUE(waitConnected(true, 30.0)) << diag("message");
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<nav_msgs::Odometry>("odom", 5);
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(10.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < end) ros::WallDuration(0.05).sleep();
  ASSERT_GT(pub.getNumSubscribers(), 0u) << "rotating_urg_driver does not subscribe to odom";
  const int published_before = g_last_scan_msgs;

  // Driving forward: refused at once, nothing published.
  publishTwist(pub, 0.2, 0.0);
  const auto t0 = std::chrono::steady_clock::now();
  scanstop_msgs::TakeScan srv = scan(50);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.5);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("the base is moving"), std::string::npos) << srv.response.message;
  EXPECT_NE(srv.response.message.find("v = 0.2 m/s"), std::string::npos) << srv.response.message;
  ros::WallDuration(0.5).sleep();  // diagnostics every 0.2 s
  EXPECT_NE(diag("base").find("the base is moving"), std::string::npos) << diag("base");
  // Turning on the spot: refused.
  publishTwist(pub, 0.0, -0.35);
  srv = scan(50);
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("w = -0.35 rad/s"), std::string::npos) << srv.response.message;

  // Standing: the scan works.
  publishTwist(pub, 0.0, 0.0);
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(diag("base"), "standing still (or no odom)");
  srv = scan(50);
  EXPECT_TRUE(srv.response.success) << srv.response.message;

  // The base starts moving during a scan (after its 10th plane): the scan is discarded.
  std::atomic<uint32_t> done{0};
  ros::Subscriber progress = nh.subscribe<scanstop_msgs::Progress>(
      "scanner/progress", 20, [&done](const scanstop_msgs::Progress::ConstPtr& m) { done = m->done; });
  ros::WallDuration(0.5).sleep();
  done = 0;
  auto running = std::async(std::launch::async, [] { return scan(400); });
  const ros::WallTime end2 = ros::WallTime::now() + ros::WallDuration(20.0);
  while (done < 10 && ros::WallTime::now() < end2) ros::WallDuration(0.01).sleep();
  ASSERT_GE(done, 10u) << "no progress from the scan";
  publishTwist(pub, 0.1, 0.0);
  publishTwist(pub, 0.0, 0.0);  // stopped again before the scan ends: it is discarded all the same
  srv = running.get();
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("the scan is discarded: the base moved during it"), std::string::npos)
      << srv.response.message;
  ros::WallDuration(0.3).sleep();
  EXPECT_EQ(g_last_scan_msgs, published_before + 1) << "a refused or discarded scan was published";
  // Standing still: scans work again.
  srv = scan(50);
  EXPECT_TRUE(srv.response.success) << srv.response.message;
}

TEST(StaleStream, HandshakeStopsTheStreamAndScans) {
  ASSERT_TRUE(waitConnected(true, 30.0)) << "never connected: " << diag("message");
  EXPECT_EQ(diag("SCIP 1.1 switches"), "0");
  // Stream lines that arrived between the drain and QT's echo were skipped (how many depends on
  // timing); after QT no more come: a scan skips nothing (a running stream would add ~36 lines
  // every 20 ms).
  const int skipped = std::stoi(diag("skipped lines"));
  EXPECT_LT(skipped, 100);
  const scanstop_msgs::TakeScan srv = scan(50);
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.counts.planes_dropped, 0u);
  EXPECT_GT(srv.response.counts.valid_points, 30000u);
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(std::stoi(diag("skipped lines")), skipped);
  EXPECT_EQ(diag("plane re-reads"), "0");
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "urg_driver_rostest");
  ros::NodeHandle nh, pnh("~");
  g_control = pnh.param<std::string>("control", "");  // the emulator's fault FIFO (fault tests only)
  ros::Subscriber diag_sub = nh.subscribe("/diagnostics", 10, onDiagnostics);
  ros::Subscriber scan_sub = nh.subscribe("scanner/last_scan", 2, onLastScan);
  tf2_ros::StaticTransformBroadcaster odom_tf;
  scanstop::Pose2D odom_pose(1.5, -0.5, 0.25);
  odom_tf.sendTransform(ros_conv::toTransformMsg(odom_pose, "odom", "base_link", ros::Time::now()));
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int rc = RUN_ALL_TESTS();
  ros::shutdown();
  return rc;
}
