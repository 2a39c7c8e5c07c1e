// gtests of the scan geometry, plane assembly and full scans through the driver against the
// in-process emulators, including every transport fault: the cloud taken under faults must equal
// the clean one (re-read planes) or differ only by dropped (all-NaN) planes, and the counts say so.
#include <gtest/gtest.h>

#include <cmath>

#include "emulated_rig.h"
#include "scanstop_common/error.h"
#include "scanstop_urg/driver.h"
#include "scanstop_urg/scanner.h"
#include "scanstop_urg/standstill.h"

namespace scanstop {
namespace urg {
namespace {

using testing::fastConfig;
using testing::Rig;
using testing::rigFactory;

constexpr int kPlanes = 50;

bool samePoint(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  if (!a.allFinite() || !b.allFinite()) return !a.allFinite() && !b.allFinite();
  return a == b;
}

/// Number of points that differ between two clouds of the same layout (NaN == NaN).
size_t differences(const PointCloud& a, const PointCloud& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  size_t d = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) d += samePoint(a.points[i], b.points[i]) ? 0 : 1;
  return d;
}

bool planeAllNan(const PointCloud& c, int plane) {
  for (uint32_t b = 0; b < c.width; ++b)
    if (c.points[plane * c.width + b].allFinite()) return false;
  return true;
}

ScanResult cleanScan() {
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  return driver.takeScan(kPlanes);
}

TEST(Geometry, SameConventionAsTheSimulator) {
  ScanGeometry g;
  g.mount_offset_m = 0.03;
  g.x_offset_m = 0.1;
  const float eps = 1e-6f;
  // Beam of step 384 (beam 340) points up; step 640 (beam 596) along the plane's horizontal axis.
  EXPECT_TRUE(g.direction(0, 100, 384 - 44).isApprox(Eigen::Vector3f(0, 0, 1), eps));
  EXPECT_TRUE(g.direction(0, 100, 640 - 44).isApprox(Eigen::Vector3f(1, 0, 0), eps));
  EXPECT_TRUE(g.direction(50, 100, 640 - 44).isApprox(Eigen::Vector3f(0, 1, 0), eps));
  EXPECT_TRUE(g.direction(25, 100, 128 - 44).isApprox(Eigen::Vector3f(-std::sqrt(0.5f), -std::sqrt(0.5f), 0), 1e-5f));
  // Plane k turned k * pi / N; mount offset along the plane.
  EXPECT_TRUE(g.origin(0, 100).isApprox(Eigen::Vector3f(0.13f, 0, 0.45f), eps));
  EXPECT_TRUE(g.origin(50, 100).isApprox(Eigen::Vector3f(0.1f, 0.03f, 0.45f), eps));
  EXPECT_EQ(g.beams(), 682);
  g.first_step = 800;
  EXPECT_THROW(g.validate(), ConfigError);
}

TEST(Geometry, RangesFromValues) {
  ScanGeometry g;
  EXPECT_TRUE(std::isnan(rangeFromValue(0, g)));
  EXPECT_TRUE(std::isnan(rangeFromValue(1, g)));
  EXPECT_TRUE(std::isnan(rangeFromValue(19, g)));
  EXPECT_FLOAT_EQ(rangeFromValue(20, g), 0.02f);
  EXPECT_FLOAT_EQ(rangeFromValue(5600, g), 5.6f);
  EXPECT_TRUE(std::isnan(rangeFromValue(5601, g)));
  PointCloud c = emptyScan(g, 2);
  std::vector<uint32_t> v(682, 1000);
  v[0] = 7;
  EXPECT_EQ(assemblePlane(c, g, 1, 2, v), 681u);
  EXPECT_TRUE(std::isnan(c.ranges[682]));
  EXPECT_FLOAT_EQ(c.ranges[683], 1.0f);
  EXPECT_TRUE(c.points[683].isApprox(g.origin(1, 2) + g.direction(1, 2, 1), 1e-6f));
  // Every beam of a plane goes along direction() exactly.
  std::vector<uint32_t> all(682, 2345);
  PointCloud c2 = emptyScan(g, 3);
  assemblePlane(c2, g, 2, 3, all);
  for (int b = 0; b < 682; ++b) ASSERT_EQ(c2.points[2 * 682 + b], g.origin(2, 3) + 2.345f * g.direction(2, 3, b)) << b;
  v.pop_back();
  EXPECT_THROW(assemblePlane(c, g, 1, 2, v), std::invalid_argument);
}

TEST(Driver, CleanScanLiesOnTheRoomSurfaces) {
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  int progress_calls = 0;
  const ScanResult r = driver.takeScan(kPlanes, [&](int done, int total) {
    ++progress_calls;
    EXPECT_EQ(total, kPlanes);
    EXPECT_EQ(done, progress_calls);
  });
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(progress_calls, kPlanes);
  EXPECT_EQ(r.cloud.height, static_cast<uint32_t>(kPlanes));
  EXPECT_EQ(r.cloud.width, 682u);
  EXPECT_EQ(r.raw_points, kPlanes * 682u);
  EXPECT_EQ(r.planes_dropped, 0u);
  EXPECT_EQ(r.plane_retries, 0u);
  EXPECT_GT(r.error_codes, 0u);  // the dark patch
  EXPECT_EQ(r.valid_points, r.cloud.countFinite());
  EXPECT_GT(r.valid_points, kPlanes * 682u * 9 / 10);
  // A flat-walled room: the filter removes almost nothing.
  EXPECT_LT(r.outliers_removed, r.raw_points / 100);
  // Every point, taken to the world frame, lies on a wall, the floor or the ceiling (1 mm steps).
  const BoxRoomScene& s = rig.scene;
  const double c = std::cos(s.robot_yaw), sn = std::sin(s.robot_yaw);
  size_t checked = 0;
  for (const auto& p : r.cloud.points) {
    if (!p.allFinite()) continue;
    const double wx = s.robot_x + c * p.x() - sn * p.y(), wy = s.robot_y + sn * p.x() + c * p.y(), wz = p.z();
    const double d = std::min({std::abs(wx - s.x_min), std::abs(wx - s.x_max), std::abs(wy - s.y_min),
                               std::abs(wy - s.y_max), std::abs(wz), std::abs(wz - s.z_max)});
    ASSERT_LT(d, 0.0012) << p.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, r.valid_points);
  const DriverStats st = driver.stats();
  EXPECT_TRUE(st.connected);
  EXPECT_EQ(st.scans_ok, 1u);
  EXPECT_EQ(st.scip11_switches, 1u);  // the emulated URG boots in SCIP 1.1
  EXPECT_NE(st.state.find("URG-04LX"), std::string::npos) << st.state;
}

TEST(Driver, FourHundredPlanesAndLaserOffAtTheEnd) {
  Rig rig;
  {
    UrgDriver driver(fastConfig(), rigFactory(rig));
    const ScanResult r = driver.takeScan(400);
    ASSERT_TRUE(r.success) << r.message;
    EXPECT_EQ(r.raw_points, 272800u);
    EXPECT_EQ(r.cloud.size(), 272800u);
    EXPECT_EQ(r.valid_points + r.error_codes + r.outliers_removed, 272800u);  // nothing out of range here
    EXPECT_EQ(rig.urg.scans(), 400u);
    EXPECT_TRUE(rig.urg.laserOn());
  }
  EXPECT_FALSE(rig.urg.laserOn());  // QT when the driver goes away
}

TEST(Driver, CorruptSumsAndDroppedBytesAreReRead) {
  const ScanResult clean = cleanScan();
  ASSERT_TRUE(clean.success) << clean.message;
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  ASSERT_TRUE(driver.connect());
  rig.faults.corruptChecksums(3);  // three bad reads of one plane: the fourth succeeds
  ScanResult r = driver.takeScan(kPlanes);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 3u);
  EXPECT_EQ(r.planes_dropped, 0u);
  EXPECT_EQ(driver.stats().checksum_errors, 3u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  rig.faults.dropBytes(3, 3);
  r = driver.takeScan(kPlanes);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 3u);
  EXPECT_EQ(r.planes_dropped, 0u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  // Stale lines and garbage before a reply: skipped on the way to the echo, nothing re-read.
  rig.noise_before_next_reply = "0?X0CB1DhI\nGD0044072501;9999\n00P\n" + std::string(300, '#') + "\n\x01\x02\n";
  r = driver.takeScan(kPlanes);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 0u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  EXPECT_GE(driver.stats().skipped_lines, 3u);
}

TEST(Driver, PlaneDroppedAfterBoundedRetries) {
  const ScanResult clean = cleanScan();
  Rig rig;
  DriverConfig config = fastConfig();
  UrgDriver driver(config, rigFactory(rig));
  ASSERT_TRUE(driver.connect());
  int hits = 0;
  const ScanResult r = driver.takeScan(kPlanes, [&](int done, int) {
    if (done == 10) {
      rig.faults.corruptChecksums(config.scanner.max_plane_retries + 1);  // plane 10 fails every read
      ++hits;
    }
  });
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(hits, 1);
  EXPECT_EQ(r.planes_dropped, 1u);
  EXPECT_EQ(r.plane_retries, static_cast<uint32_t>(config.scanner.max_plane_retries));
  EXPECT_TRUE(planeAllNan(r.cloud, 10));
  EXPECT_FALSE(planeAllNan(clean.cloud, 10));
  // Only plane 10 and the outlier decisions next to it differ.
  for (int p = 0; p < kPlanes; ++p) {
    if (p >= 9 && p <= 11) continue;
    for (uint32_t b = 0; b < 682; ++b)
      ASSERT_TRUE(samePoint(r.cloud.points[p * 682 + b], clean.cloud.points[p * 682 + b])) << p << " " << b;
  }
  EXPECT_EQ(driver.stats().planes_dropped, 1u);
}

TEST(Driver, SilenceIsSurvivedOrReportedAndReconnected) {
  const ScanResult clean = cleanScan();
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  ASSERT_TRUE(driver.connect());
  rig.silent_replies = 2;  // a short silence: two timeouts, then the plane arrives
  ScanResult r = driver.takeScan(kPlanes);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 2u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  EXPECT_EQ(driver.stats().timeouts, 2u);
  // A long silence: planes in a row are lost, the scan fails clearly, the driver reconnects.
  rig.silent_replies = 1000;
  r = driver.takeScan(kPlanes);
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(r.device_lost);
  EXPECT_NE(r.message.find("stopped answering"), std::string::npos) << r.message;
  EXPECT_FALSE(driver.connected());
  EXPECT_FALSE(driver.connect());  // still silent
  EXPECT_NE(driver.stats().state.find("disconnected"), std::string::npos);
  rig.silent_replies = 0;
  ASSERT_TRUE(driver.connect()) << driver.stats().state;
  r = driver.takeScan(kPlanes);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  EXPECT_EQ(driver.stats().connection_losses, 1u);
}

TEST(Driver, PowerCycleToScip11MidScanIsRecovered) {
  const ScanResult clean = cleanScan();
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  const ScanResult r = driver.takeScan(kPlanes, [&](int done, int) {
    if (done == 20) rig.urg.powerCycle();
  });
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 1u);
  EXPECT_EQ(r.planes_dropped, 0u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
  EXPECT_EQ(driver.stats().scip11_switches, 2u);
}

TEST(Driver, LaserSwitchedOffMidScanIsSwitchedOnAgain) {
  const ScanResult clean = cleanScan();
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  const ScanResult r = driver.takeScan(kPlanes, [&](int done, int) {
    if (done == 5) rig.urg.handleLine("QT");
  });
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_EQ(r.plane_retries, 0u);
  EXPECT_EQ(differences(r.cloud, clean.cloud), 0u);
}

TEST(Driver, UnplugFailsTheScanAndReconnectsWhenBack) {
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  const ScanResult r = driver.takeScan(kPlanes, [&](int done, int) {
    if (done == 7) rig.unplugged = true;
  });
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(r.device_lost);
  EXPECT_NE(r.message.find("unplugged"), std::string::npos) << r.message;
  EXPECT_FALSE(driver.connected());
  const ScanResult r2 = driver.takeScan(kPlanes);
  EXPECT_FALSE(r2.success);
  EXPECT_NE(r2.message.find("not connected"), std::string::npos) << r2.message;
  EXPECT_NE(r2.message.find("no such device"), std::string::npos) << r2.message;
  rig.unplugged = false;
  const ScanResult r3 = driver.takeScan(kPlanes);
  ASSERT_TRUE(r3.success) << r3.message;
  const DriverStats st = driver.stats();
  EXPECT_EQ(st.connects, 2u);
  EXPECT_EQ(st.connection_losses, 1u);
  EXPECT_EQ(st.scans_ok, 1u);
  EXPECT_EQ(st.scans_failed, 2u);
}

TEST(Driver, IdleHangUpIsNoticed) {
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  ASSERT_TRUE(driver.connect());
  EXPECT_TRUE(driver.checkLink());
  rig.unplugged = true;
  EXPECT_FALSE(driver.checkLink());
  EXPECT_NE(driver.stats().state.find("hung up"), std::string::npos) << driver.stats().state;
  EXPECT_EQ(driver.stats().connection_losses, 1u);
  rig.unplugged = false;
  EXPECT_TRUE(driver.connect());
}

TEST(Driver, PlatformStallFailsTheScanClearlyAndTheNextScanRehomes) {
  Rig rig;
  UrgDriver driver(fastConfig(), rigFactory(rig));
  ASSERT_TRUE(driver.connect());
  rig.stepper.injectStall(1);
  const ScanResult r = driver.takeScan(kPlanes);
  EXPECT_FALSE(r.success);
  EXPECT_FALSE(r.device_lost);
  EXPECT_NE(r.message.find("motor stall"), std::string::npos) << r.message;
  const ScanResult r2 = driver.takeScan(kPlanes);
  ASSERT_TRUE(r2.success) << r2.message;
  EXPECT_EQ(rig.stepper.position(), 0);  // parked
}

TEST(Driver, HandshakeFromTimeStampModeAndFailures) {
  Rig rig;
  rig.urg.handleLine("SCIP2.0");
  rig.urg.handleLine("TM0");  // a crashed client left time-stamp mode on
  rig.noise_before_next_reply = "0?X0CB1DhI\n\nTM1;4\n00P\n" + std::string(200, '~') + "\n";  // stale stream, garbage
  UrgDriver driver(fastConfig(), rigFactory(rig));
  ASSERT_TRUE(driver.connect()) << driver.stats().state;
  EXPECT_EQ(driver.stats().scip11_switches, 0u);
  EXPECT_GE(driver.stats().skipped_lines, 4u);

  // An endless MD stream left running by a crashed client: skipped on the way to QT's echo, stopped.
  Rig streaming;
  streaming.urg.handleLine("SCIP2.0");
  streaming.urg.handleLine("MD0044072501000");
  ASSERT_TRUE(streaming.urg.streaming());
  UrgDriver ds(fastConfig(), rigFactory(streaming));
  ASSERT_TRUE(ds.connect()) << ds.stats().state;
  EXPECT_FALSE(streaming.urg.streaming());
  EXPECT_GE(ds.stats().skipped_lines, 36u);  // echo, 99b, time, 32 data lines, blank
  EXPECT_TRUE(ds.takeScan(kPlanes).success);

  // Garbage without a line end swallows the echo of the first reply: a timeout, then recovery.
  Rig swallowed;
  swallowed.noise_before_next_reply = std::string(200, '~');
  UrgDriver d1(fastConfig(), rigFactory(swallowed));
  ASSERT_TRUE(d1.connect()) << d1.stats().state;
  EXPECT_EQ(d1.stats().timeouts, 1u);

  Rig faulty;
  faulty.urg.setLaserFault(true);
  UrgDriver d2(fastConfig(), rigFactory(faulty));
  EXPECT_FALSE(d2.connect());
  EXPECT_NE(d2.stats().state.find("laser fault"), std::string::npos) << d2.stats().state;

  Rig rig3;
  DriverConfig c = fastConfig();
  c.urg.first_step = c.scanner.geometry.first_step = 10;
  UrgDriver d3(c, rigFactory(rig3));
  EXPECT_FALSE(d3.connect());
  EXPECT_NE(d3.stats().state.find("AMIN"), std::string::npos) << d3.stats().state;
}

TEST(Driver, ConfigValidation) {
  DriverConfig c = fastConfig();
  c.scanner.max_plane_retries = -1;
  EXPECT_THROW(UrgDriver(c, serialStreamFactory()), ConfigError);
  c = fastConfig();
  c.urg_port.clear();
  EXPECT_THROW(UrgDriver(c, serialStreamFactory()), ConfigError);
  c = fastConfig();
  c.scanner.geometry.height_m = 10.0;
  EXPECT_THROW(UrgDriver(c, serialStreamFactory()), ConfigError);
}

TEST(Serial, MissingPortIsAClearError) {
  try {
    SerialPort port("/nonexistent/ttyACM9", 19200);
    FAIL() << "opened a missing port";
  } catch (const ScipError& e) {
    EXPECT_EQ(e.kind(), ScipError::Kind::kDisconnected);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ttyACM9"), std::string::npos);
  }
  EXPECT_THROW(SerialPort("/dev/null", 12345), std::invalid_argument);
}

// ---- Bad requests and safety (issue 9).

TEST(RequestChecks, ScanPlanesOnlyTheFourCounts) {
  for (long ok : {50L, 100L, 200L, 400L}) EXPECT_EQ(checkScanPlanes(ok), "") << ok;
  for (long bad : {0L, 7L, 49L, 401L, 65535L, -50L}) {
    const std::string m = checkScanPlanes(bad);
    EXPECT_NE(m.find("planes = " + std::to_string(bad)), std::string::npos) << m;
    EXPECT_NE(m.find("50, 100, 200, 400"), std::string::npos) << m;
  }
}

TEST(Standstill, AScanNeedsTheBaseStandingStill) {
  const StandstillConfig c;
  EXPECT_EQ(baseMotionProblem(0.0, 0.0, c), "");
  EXPECT_EQ(baseMotionProblem(0.01, -0.02, c), "");  // the thresholds themselves: standing (odometry noise)
  const std::string forward = baseMotionProblem(0.2, 0.0, c);
  EXPECT_NE(forward.find("the base is moving"), std::string::npos) << forward;
  EXPECT_NE(forward.find("v = 0.2 m/s"), std::string::npos) << forward;
  EXPECT_NE(baseMotionProblem(-0.05, 0.0, c), "");  // backwards
  EXPECT_NE(baseMotionProblem(0.0, 0.35, c).find("w = 0.35 rad/s"), std::string::npos);
  EXPECT_NE(baseMotionProblem(0.0, -0.03, c), "");
  EXPECT_NE(baseMotionProblem(std::nan(""), 0.0, c), "");  // a non-finite twist counts as moving
  EXPECT_NE(baseMotionProblem(0.0, double(INFINITY), c), "");
}

TEST(Standstill, ThresholdsAreValidatedWithTheParameterName) {
  StandstillConfig c;
  EXPECT_NO_THROW(c.validate());
  c.max_linear_speed_mps = -1.0;
  try {
    c.validate();
    ADD_FAILURE() << "accepted a negative threshold";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'standstill/max_linear_speed_mps' = -1 m/s is out of range [0, 0.5 m/s]"),
              std::string::npos)
        << e.what();
  }
  c = StandstillConfig();
  c.max_angular_speed_radps = std::nan("");
  EXPECT_THROW(c.validate(), ConfigError);
}

TEST(DriverConfigChecks, BadValuesNameTheParameterValueAndRange) {
  auto message = [](const DriverConfig& c) {
    try {
      c.validate();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  DriverConfig c;
  EXPECT_EQ(message(c), "");
  c.urg_baud = 12345;
  EXPECT_NE(message(c).find("'baud' = 12345 is not a supported rate (9600"), std::string::npos) << message(c);
  c = DriverConfig();
  c.platform_baud = -9600;
  EXPECT_NE(message(c).find("'platform/baud' = -9600"), std::string::npos) << message(c);
  c = DriverConfig();
  c.urg.reply_timeout_s = -1.0;
  EXPECT_NE(message(c).find("'reply_timeout_s' = -1 s is out of range [0.001, 60 s]"), std::string::npos) << message(c);
  c = DriverConfig();
  c.urg.scan_timeout_s = std::nan("");
  EXPECT_NE(message(c).find("'scan_timeout_s' = nan s"), std::string::npos) << message(c);
  c = DriverConfig();
  c.stepper.home_timeout_s = 0.0;
  EXPECT_NE(message(c).find("'platform/home_timeout_s' = 0 s is out of range"), std::string::npos) << message(c);
  c = DriverConfig();
  c.stepper.retries = -2;
  EXPECT_NE(message(c).find("'platform/retries' = -2"), std::string::npos) << message(c);
  c = DriverConfig();
  c.scanner.geometry.height_m = 7.0;
  EXPECT_NE(message(c).find("'scanner/height_m' = 7 m"), std::string::npos) << message(c);
  c = DriverConfig();
  c.scanner.max_plane_retries = 50;
  EXPECT_NE(message(c).find("max_plane_retries = 50 must be in 0..20"), std::string::npos) << message(c);
}

}  // namespace
}  // namespace urg
}  // namespace scanstop
