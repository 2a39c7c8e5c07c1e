// The emulator's protocol behaviour (time-driven, no pty) and the driver core against the emulator
// on a real pseudo-terminal: handshake, recovery of a session still open, motions, cmd_vel timeout.
#include <gtest/gtest.h>

#include <limits>

#include <chrono>
#include <cmath>
#include <thread>

#include "scanstop_pioneer/p2os_client.h"
#include "scanstop_pioneer/pioneer_driver.h"
#include "scanstop_pioneer/pty_emulator.h"
#include "scanstop_pioneer/robot_emulator.h"

namespace {

using namespace scanstop::pioneer;
using Bytes = std::vector<uint8_t>;

std::vector<Bytes> packets(RobotEmulator& emu) {
  PacketParser parser;
  const Bytes out = emu.takeOutput();
  parser.feed(out.data(), out.size());
  std::vector<Bytes> result;
  Bytes p;
  while (parser.next(p)) result.push_back(p);
  return result;
}

void send(RobotEmulator& emu, const Bytes& packet, double t) { emu.receive(packet.data(), packet.size(), t); }

TEST(Emulator, SyncStateMachineOpenEnableAndSips) {
  RobotEmulator emu{EmulatorConfig()};
  send(emu, commandPacket(cmd::kSync1), 0.0);  // out of order: ignored
  EXPECT_TRUE(packets(emu).empty());
  send(emu, commandPacket(cmd::kSync0), 0.0);
  EXPECT_EQ(packets(emu), std::vector<Bytes>{Bytes{0x00}});
  send(emu, commandPacket(cmd::kSync1), 0.0);
  EXPECT_EQ(packets(emu), std::vector<Bytes>{Bytes{0x01}});
  send(emu, commandPacket(cmd::kSync2), 0.0);
  auto reply = packets(emu);
  ASSERT_EQ(reply.size(), 1u);
  SyncInfo info;
  ASSERT_TRUE(decodeSync2Reply(reply[0].data(), reply[0].size(), info));
  EXPECT_EQ(info.subclass, "p2dx");
  EXPECT_EQ(emu.state(), EmulatorState::kConnected);
  send(emu, commandPacket(cmd::kOpen), 0.0);
  EXPECT_EQ(emu.state(), EmulatorState::kOpen);
  // Ten SIPs per second; motors disabled until ENABLE 1.
  send(emu, commandPacket(cmd::kVel, 200), 0.0);
  for (int i = 0; i <= 10; ++i) emu.advance(0.1 * i);
  auto sips = packets(emu);
  EXPECT_EQ(sips.size(), 11u);
  Sip sip;
  ASSERT_TRUE(decodeSip(sips.back().data(), sips.back().size(), sip));
  EXPECT_FALSE(sip.motorsEnabled());
  EXPECT_EQ(sip.x, 0);
  send(emu, commandPacket(cmd::kEnable, 1), 1.0);
  for (int i = 11; i <= 30; ++i) {
    send(emu, commandPacket(cmd::kPulse), 0.1 * i);
    emu.advance(0.1 * i);
  }
  sips = packets(emu);
  ASSERT_TRUE(decodeSip(sips.back().data(), sips.back().size(), sip));
  EXPECT_TRUE(sip.motorsEnabled());
  EXPECT_TRUE(sip.moving());
  EXPECT_EQ(sip.left_vel, 200);
  EXPECT_GT(emu.truePose().x, 0.2);
  EXPECT_NEAR(sip.x * 0.84e-3, emu.truePose().x, 1e-3);
  // CLOSE: back to WAIT, no more SIPs.
  send(emu, commandPacket(cmd::kClose), 3.0);
  emu.advance(3.5);
  EXPECT_EQ(emu.state(), EmulatorState::kWait);
  EXPECT_TRUE(packets(emu).empty());
}

TEST(Emulator, WatchdogStopsTheDrivesAndResumes) {
  RobotEmulator emu{EmulatorConfig()};
  emu.leaveOpen(0.0);
  send(emu, commandPacket(cmd::kVel, 300), 0.0);
  for (int i = 1; i <= 40; ++i) emu.advance(0.05 * i);  // 2 s of silence from the client
  EXPECT_NEAR(emu.linearVelocity(), 0.3, 1e-9);
  for (int i = 41; i <= 80; ++i) emu.advance(0.05 * i);
  EXPECT_TRUE(emu.watchdogTripped());
  EXPECT_NEAR(emu.linearVelocity(), 0.0, 1e-9);
  send(emu, commandPacket(cmd::kPulse), 4.0);
  for (int i = 81; i <= 100; ++i) emu.advance(0.05 * i);
  EXPECT_FALSE(emu.watchdogTripped());
  EXPECT_NEAR(emu.linearVelocity(), 0.3, 1e-9);  // resumes the last setpoint
}

TEST(Emulator, FaultsCorruptDropAndStall) {
  RobotEmulator emu{EmulatorConfig()};
  emu.leaveOpen(0.0);
  emu.command("corrupt 2", 0.0);
  emu.command("drop 1", 0.0);
  emu.command("stall on", 0.0);
  EXPECT_THROW(emu.command("stall maybe", 0.0), std::invalid_argument);
  EXPECT_THROW(emu.command("explode", 0.0), std::invalid_argument);
  send(emu, commandPacket(cmd::kVel, 200), 0.0);
  for (int i = 0; i <= 9; ++i) emu.advance(0.1 * i);
  PacketParser parser;
  const Bytes out = emu.takeOutput();
  parser.feed(out.data(), out.size());
  Bytes p;
  int good = 0;
  Sip sip;
  while (parser.next(p)) {
    ++good;
    ASSERT_TRUE(decodeSip(p.data(), p.size(), sip));
  }
  EXPECT_EQ(good, 8);  // 10 SIPs; the first corrupted and shortened, the second corrupted
  EXPECT_GE(parser.stats().checksum_errors, 2u);
  EXPECT_TRUE(sip.leftStall());
  EXPECT_TRUE(sip.rightStall());
  EXPECT_EQ(emu.truePose().x, 0.0);
}

TEST(Client, HandshakeAndRecoveryOverAPty) {
  PtyEmulator emu(EmulatorConfig(), "");
  emu.start();
  SerialPort port;
  port.open(emu.devicePath(), 9600);
  ClientConfig cc;
  P2osClient client(port, cc);
  const SyncInfo info = client.connect();
  EXPECT_EQ(info.name, "scanstop-emulator");
  EXPECT_EQ(client.recoveries(), 0u);
  Bytes payload;
  ASSERT_TRUE(client.receive(payload, 1.0));
  Sip sip;
  ASSERT_TRUE(decodeSip(payload.data(), payload.size(), sip));
  // A second client meets the session still open (the first one vanished without CLOSE).
  port.close();
  SerialPort port2;
  port2.open(emu.devicePath(), 9600);
  P2osClient client2(port2, cc);
  client2.connect();
  ASSERT_TRUE(client2.receive(payload, 1.0));  // the new session's first SIP
  EXPECT_EQ(client2.recoveries(), 1u);
  EXPECT_NE(client2.lastConnectNote().find("still open"), std::string::npos);
  EXPECT_EQ(emu.with([](RobotEmulator& e) { return e.sessionsOpened(); }), 2u);
  // A client that died after SYNC2 (robot CONNECTED, where 0 means PULSE): no echo, CLOSE, retry.
  client2.close();
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  port2.write(commandPacket(cmd::kSync0).data(), 6);
  port2.write(commandPacket(cmd::kSync1).data(), 6);
  port2.write(commandPacket(cmd::kSync2).data(), 6);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(emu.with([](RobotEmulator& e) { return e.state(); }), EmulatorState::kConnected);
  P2osClient client3(port2, cc);
  client3.connect();
  ASSERT_TRUE(client3.receive(payload, 1.0));  // SIPs flow: the session is open
  EXPECT_TRUE(isStandardSipType(payload[0]));
  EXPECT_EQ(emu.with([](RobotEmulator& e) { return e.state(); }), EmulatorState::kOpen);
  emu.stop();
}

TEST(Client, RobotStopsByItsWatchdogWhenTheDriverFallsSilent) {
  // A driver that crashes mid-motion sends nothing more (no STOP): the robot's own 2 s watchdog
  // (P2OS; modelled by the emulator) stops the drives, over the real pty link.
  PtyEmulator emu(EmulatorConfig(), "");
  emu.start();
  SerialPort port;
  port.open(emu.devicePath(), 9600);
  P2osClient client(port, ClientConfig());
  client.connect();
  client.send(commandPacket(cmd::kVel, 300));
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  EXPECT_GT(emu.with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.25);
  EXPECT_FALSE(emu.with([](RobotEmulator& e) { return e.watchdogTripped(); }));
  // Silence: 2 s watchdog, then 1 s to brake from 0.3 m/s at 0.3 m/s^2.
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  EXPECT_TRUE(emu.with([](RobotEmulator& e) { return e.watchdogTripped(); }));
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  EXPECT_EQ(emu.with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.0);
  emu.stop();
}

TEST(Client, NoRobotFailsWithAClearMessage) {
  PtyEmulator emu(EmulatorConfig(), "");
  emu.start();
  emu.command("silence 30");
  SerialPort port;
  port.open(emu.devicePath(), 9600);
  ClientConfig cc;
  cc.reply_timeout_s = 0.2;
  cc.sync_attempts = 2;
  cc.close_wait_s = 0.05;
  P2osClient client(port, cc);
  try {
    client.connect();
    FAIL() << "expected ProtocolError";
  } catch (const ProtocolError& e) {
    EXPECT_NE(std::string(e.what()).find("no reply to SYNC0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(port.open("/nonexistent/tty", 9600), LinkError);
  emu.stop();
}

class DriverOnEmulator : public ::testing::Test {
 protected:
  void SetUp() override {
    EmulatorConfig ec;
    // The robot's 15-bit x counter starts 0.15 m before its wrap (0x7FFF units * 0.84 mm).
    ec.start_x_mm = 0x7FFF * 0.84 - 150.0;
    emu_ = std::make_unique<PtyEmulator>(ec, "");
    emu_->start();
    DriverConfig config;
    config.port = emu_->devicePath();
    config.reconnect_period_s = 0.2;
    driver_ = std::make_unique<PioneerDriver>(config);
    driver_->start();
    for (int i = 0; i < 100 && !driver_->status().have_sip; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(driver_->status().have_sip) << driver_->status().last_error;
  }
  void TearDown() override {
    driver_->stop();
    emu_->stop();
  }
  scanstop::Pose2D truth() {
    return emu_->with([](RobotEmulator& e) { return e.truePose(); });
  }
  std::unique_ptr<PtyEmulator> emu_;
  std::unique_ptr<PioneerDriver> driver_;
};

TEST_F(DriverOnEmulator, ForwardAcrossThe15BitWrap) {
  // Along the robot's own x axis: the counter wraps from 0x7FFF to 0 after 0.15 m.
  const MotionResult f = driver_->forward(0.4);
  ASSERT_TRUE(f.success) << f.message;
  EXPECT_NEAR(f.achieved, 0.4, 0.01);
  EXPECT_NEAR(f.odom.x, truth().x, 0.003);
  EXPECT_NEAR(f.odom.y, 0.0, 0.003);
  const DriverStatus s = driver_->status();
  EXPECT_LT(s.sip.x, 1000);  // the counter did wrap
  const MotionResult b = driver_->forward(-0.4);
  ASSERT_TRUE(b.success) << b.message;
  EXPECT_NEAR(driver_->status().odom.x, truth().x, 0.003);
  EXPECT_GT(driver_->status().sip.x, 0x7000);  // and wrapped back
}

TEST_F(DriverOnEmulator, RotateAndForwardMatchTheRobot) {
  const MotionResult r = driver_->rotate(M_PI / 2);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_NEAR(r.achieved, M_PI / 2, 0.02);
  EXPECT_NEAR(truth().yaw, r.achieved, 0.005);
  const MotionResult f = driver_->forward(0.4);
  ASSERT_TRUE(f.success) << f.message;
  EXPECT_NEAR(f.achieved, 0.4, 0.01);
  EXPECT_NEAR(truth().y, 0.4, 0.01);
  EXPECT_NEAR(f.odom.y, truth().y, 0.003);
  EXPECT_FALSE(driver_->forward(7.0).success);  // beyond max_forward
}

TEST_F(DriverOnEmulator, CmdVelTimeoutStopsTheRobot) {
  ASSERT_TRUE(driver_->commandVelocity(0.3, 0.0));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_GT(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.02);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // no new command: timeout 0.5 s
  EXPECT_NEAR(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.0, 1e-9);
  EXPECT_EQ(driver_->status().cmd_vel_timeouts, 1u);
}

// The ROS master gone (issue #22 class 5): the node's watchdog calls halt(): a running forward motion
// stops short and says why, teleoperation stops, and motions and velocity commands are refused until
// allowMotion() (the master back).
TEST_F(DriverOnEmulator, HaltStopsARunningMotionAndRefusesMotionsUntilAllowed) {
  const std::string why = "the ROS master at http://127.0.0.1:11471 is unreachable (gone for 1.0 s)";
  MotionResult running;
  std::thread motion([&] { running = driver_->forward(2.0); });
  // Poll until the robot drives (deadline 10 s), then halt.
  for (int i = 0; i < 200 && emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }) < 0.05; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_GT(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.05);
  driver_->halt(why);
  motion.join();
  EXPECT_FALSE(running.success);
  EXPECT_NE(running.message.find("stopped: " + why), std::string::npos) << running.message;
  EXPECT_LT(running.achieved, 1.5);
  // The robot comes to a standstill (polled, deadline 5 s).
  for (int i = 0; i < 100 && emu_->with([](RobotEmulator& e) { return std::abs(e.linearVelocity()); }) > 1e-9; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_NEAR(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.0, 1e-9);
  const scanstop::Pose2D stopped = truth();
  const MotionResult refused = driver_->rotate(0.5);
  EXPECT_FALSE(refused.success);
  EXPECT_EQ(refused.message, "refused: " + why);
  std::string reason;
  EXPECT_FALSE(driver_->commandVelocity(0.2, 0.0, &reason));
  EXPECT_EQ(reason, "refused: " + why);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(truth().toString(), stopped.toString());  // nothing moved
  driver_->allowMotion();
  const MotionResult again = driver_->rotate(0.5);
  EXPECT_TRUE(again.success) << again.message;
}

// ---- Bad requests and speed bounds (issue 9).

TEST_F(DriverOnEmulator, BadRequestsAreRefusedAndMoveNothing) {
  const scanstop::Pose2D before = truth();
  const scanstop::Pose2D odom_before = driver_->status().odom;
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    bool rotate;
    double target;
    std::string expected;
  };
  for (const Case& c : {Case{true, 50.0, "angle_rad = 50.000 must be finite and within [-6.283, 6.283]"},
                        Case{true, -7.0, "angle_rad = -7.000"}, Case{true, std::nan(""), "angle_rad = nan"},
                        Case{true, -inf, "angle_rad = -inf"},
                        Case{false, 100.0, "distance_m = 100.000 must be finite and within [-5.000, 5.000]"},
                        Case{false, -5.5, "distance_m = -5.500"}, Case{false, std::nan(""), "distance_m = nan"},
                        Case{false, inf, "distance_m = inf"}}) {
    const MotionResult r = c.rotate ? driver_->rotate(c.target) : driver_->forward(c.target);
    EXPECT_FALSE(r.success);
    EXPECT_NE(r.message.find(c.expected), std::string::npos) << r.message;
    EXPECT_LT(r.duration_s, 1e-9);  // refused before anything was sent
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(truth().toString(), before.toString());
  EXPECT_EQ(driver_->status().odom.toString(), odom_before.toString());
  EXPECT_EQ(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.0);
  std::string reason;
  EXPECT_FALSE(driver_->commandVelocity(std::nan(""), 0.0, &reason));
  EXPECT_EQ(reason, "velocity is not finite");
}

TEST_F(DriverOnEmulator, CmdVelIsClampedToTheSpeedBounds) {
  // A client asks for 3 m/s and 10 rad/s: the robot gets max_linear_speed 0.5 m/s (then max_angular_speed).
  // (Commands repeated every 0.1 s as a teleoperation client does; the robot accelerates at 0.3 m/s^2.)
  for (int i = 0; i < 25; ++i) {
    ASSERT_TRUE(driver_->commandVelocity(3.0, 0.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_NEAR(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.5, 1e-6);
  for (int i = 0; i < 25; ++i) {
    ASSERT_TRUE(driver_->commandVelocity(0.0, -10.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  // RVEL is sent in whole deg/s: 57 deg/s.
  EXPECT_NEAR(emu_->with([](RobotEmulator& e) { return e.angularVelocity(); }), -1.0, 0.01);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // command timeout: stopped
  EXPECT_EQ(emu_->with([](RobotEmulator& e) { return e.angularVelocity(); }), 0.0);
  EXPECT_EQ(emu_->with([](RobotEmulator& e) { return e.linearVelocity(); }), 0.0);
}

TEST(DriverConfigChecks, MotionSpeedsMustStayWithinTheSpeedBounds) {
  DriverConfig c;
  c.port = "/dev/null";
  EXPECT_NO_THROW(c.validate());
  c.motion.linear_speed_mps = 0.8;  // above max_linear_speed 0.5
  try {
    c.validate();
    ADD_FAILURE() << "accepted motion/linear_speed above max_linear_speed";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("'motion/linear_speed_mps' = 0.8 m/s is out of range [0.01, 0.5 m/s]"),
              std::string::npos)
        << e.what();
  }
  c = DriverConfig();
  c.port = "/dev/null";
  c.max_angular_speed_radps = 0.2;  // below motion/angular_speed 0.35
  EXPECT_THROW(c.validate(), std::exception);
  c = DriverConfig();
  c.port = "/dev/null";
  c.cmd_vel_timeout_s = -1.0;
  try {
    c.validate();
    ADD_FAILURE() << "accepted a negative cmd_vel_timeout";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("'cmd_vel_timeout_s' = -1 s is out of range [0.05, 10 s]"), std::string::npos)
        << e.what();
  }
  c = DriverConfig();
  c.port = "/dev/null";
  c.motion.max_forward_m = 1000.0;
  EXPECT_THROW(c.validate(), std::exception);
}

}  // namespace
