// P2OS codec and odometry against the worked examples of PROTOCOL_FACTS part 2.
#include <gtest/gtest.h>

#include <cmath>

#include "scanstop_pioneer/odometry.h"
#include "scanstop_pioneer/p2os_protocol.h"

namespace {

using namespace scanstop::pioneer;
using Bytes = std::vector<uint8_t>;

Bytes payloadOf(const Bytes& packet) { return Bytes(packet.begin() + 3, packet.end() - 2); }

// The example SIP of PROTOCOL_FACTS 2.5 (checksum verified there).
const Bytes kExampleSip{0xFA, 0xFB, 0x21, 0x33, 0xE8, 0x03, 0xF0, 0x7F, 0x00, 0x04, 0x64, 0x00,
                        0x78, 0x00, 0x7D, 0x00, 0x00, 0x00, 0x04, 0x01, 0x00, 0x00, 0x02, 0x00,
                        0x4A, 0x07, 0x01, 0x93, 0x0E, 0x00, 0x00, 0x00, 0x00, 0x00, 0x57, 0x90};

TEST(Protocol, CommandPacketsMatchTheWorkedExamples) {
  EXPECT_EQ(commandPacket(cmd::kSync0), (Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00}));
  EXPECT_EQ(commandPacket(cmd::kPulse), (Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00}));
  EXPECT_EQ(commandPacket(cmd::kSync1), (Bytes{0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01}));
  EXPECT_EQ(commandPacket(cmd::kOpen), (Bytes{0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01}));
  EXPECT_EQ(commandPacket(cmd::kSync2), (Bytes{0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02}));
  EXPECT_EQ(commandPacket(cmd::kClose), (Bytes{0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02}));
  EXPECT_EQ(commandPacket(cmd::kStop), (Bytes{0xFA, 0xFB, 0x03, 0x1D, 0x00, 0x1D}));
  EXPECT_EQ(commandPacket(cmd::kEnable, 1), (Bytes{0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B}));
  EXPECT_EQ(commandPacket(cmd::kVel, 200), (Bytes{0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xC8, 0x00, 0xD3, 0x3B}));
  EXPECT_EQ(commandPacket(cmd::kVel, -200), (Bytes{0xFA, 0xFB, 0x06, 0x0B, 0x1B, 0xC8, 0x00, 0xD3, 0x1B}));
  EXPECT_EQ(commandPacket(cmd::kRVel, 10), (Bytes{0xFA, 0xFB, 0x06, 0x15, 0x3B, 0x0A, 0x00, 0x1F, 0x3B}));
  EXPECT_EQ(cmd::kEStop, 55);
  EXPECT_THROW(commandPacket(cmd::kVel, 40000), std::invalid_argument);
  EXPECT_THROW(framePacket(Bytes(199, 0)), std::invalid_argument);
  EXPECT_THROW(framePacket(Bytes()), std::invalid_argument);
}

TEST(Protocol, ChecksumPairsAndOddByte) {
  // Pairs are big-endian, summed mod 2^16; an odd last byte is XORed.
  EXPECT_EQ(checksum(Bytes{0x0B, 0x3B, 0xC8, 0x00}), 0xD33B);
  EXPECT_EQ(checksum(Bytes{0x1D}), 0x001D);
  EXPECT_EQ(checksum(Bytes{0x04, 0x3B, 0x01, 0x00}), 0x053B);  // ENABLE 1
  EXPECT_EQ(checksum(Bytes{0x04, 0x3B, 0x01}), 0x043A);        // 0x043B ^ 0x01
  EXPECT_EQ(checksum(Bytes{0xFF, 0xFF, 0x00, 0x02}), 0x0001);  // wraps modulo 2^16
  EXPECT_EQ(checksum(payloadOf(kExampleSip)), 0x5790);
}

TEST(Protocol, Sync2ReplyMatchesTheWorkedExample) {
  const Bytes expected{0xFA, 0xFB, 0x16, 0x02, 0x4D, 0x79, 0x42, 0x6F, 0x74, 0x00, 0x50, 0x69, 0x6F,
                       0x6E, 0x65, 0x65, 0x72, 0x00, 0x70, 0x32, 0x64, 0x78, 0x00, 0xD3, 0x6D};
  EXPECT_EQ(framePacket(encodeSync2Reply({"MyBot", "Pioneer", "p2dx"})), expected);
  SyncInfo info;
  const Bytes payload = payloadOf(expected);
  ASSERT_TRUE(decodeSync2Reply(payload.data(), payload.size(), info));
  EXPECT_EQ(info.name, "MyBot");
  EXPECT_EQ(info.robot_class, "Pioneer");
  EXPECT_EQ(info.subclass, "p2dx");
  std::string error;
  EXPECT_FALSE(decodeSync2Reply(payload.data(), payload.size() - 1, info, &error));
  EXPECT_NE(error.find("subclass"), std::string::npos) << error;
}

TEST(Protocol, ExampleSipDecodes) {
  PacketParser parser;
  parser.feed(kExampleSip.data(), kExampleSip.size());
  Bytes payload;
  ASSERT_TRUE(parser.next(payload));
  Sip sip;
  std::string error;
  ASSERT_TRUE(decodeSip(payload.data(), payload.size(), sip, &error)) << error;
  EXPECT_TRUE(sip.moving());
  EXPECT_EQ(sip.x, 1000);
  EXPECT_EQ(sip.y, 0x7FF0);
  EXPECT_EQ(sip.th, 1024);
  EXPECT_EQ(sip.left_vel, 100);
  EXPECT_EQ(sip.right_vel, 120);
  EXPECT_DOUBLE_EQ(sip.batteryVolts(), 12.5);
  EXPECT_FALSE(sip.stalled());
  EXPECT_EQ(sip.frontBumpers(), 0);
  EXPECT_EQ(sip.control, 1024);
  EXPECT_TRUE(sip.motorsEnabled());
  ASSERT_EQ(sip.sonar.size(), 2u);
  EXPECT_EQ(sip.sonar[0].first, 0);
  EXPECT_EQ(sip.sonar[0].second, 1866);
  EXPECT_EQ(sip.sonar[1].first, 1);
  EXPECT_EQ(sip.sonar[1].second, 3731);
  EXPECT_TRUE(sip.has_io);
  const RobotParams p2dx;
  EXPECT_NEAR(sip.x * p2dx.dist_conv_mm, 840.0, 1e-9);
  EXPECT_NEAR(sip.th * p2dx.angle_conv_rad, 1.571, 1e-3);
  EXPECT_NEAR(sip.sonar[0].second * p2dx.range_conv_mm, 500.0, 0.2);
  EXPECT_NEAR(sip.sonar[1].second * p2dx.range_conv_mm, 1000.0, 0.2);
  // encodeSip reproduces the example byte for byte.
  EXPECT_EQ(framePacket(encodeSip(sip)), kExampleSip);
}

TEST(Protocol, SipStallAndBumperBits) {
  Sip sip;
  sip.stall_bump_lo = 0x01 | (0x03 << 1);
  sip.stall_bump_hi = 0x01 | (0x10 << 1);
  EXPECT_TRUE(sip.leftStall());
  EXPECT_TRUE(sip.rightStall());
  EXPECT_EQ(sip.rearBumpers(), 0x03);
  EXPECT_EQ(sip.frontBumpers(), 0x10);
}

TEST(Protocol, TruncatedOrForeignSipIsRejectedWithReason) {
  const Bytes payload = payloadOf(kExampleSip);
  Sip sip;
  std::string error;
  EXPECT_FALSE(decodeSip(payload.data(), 10, sip, &error));
  EXPECT_NE(error.find("truncated"), std::string::npos) << error;
  EXPECT_FALSE(decodeSip(payload.data(), 24, sip, &error));  // sonar count 2 needs 26 bytes
  EXPECT_NE(error.find("sonar count 2"), std::string::npos) << error;
  Bytes other = payload;
  other[0] = 0x20;  // CONFIG packet
  EXPECT_FALSE(decodeSip(other.data(), other.size(), sip, &error));
  EXPECT_NE(error.find("0x20"), std::string::npos) << error;
  // Newer firmware: extra trailing bytes are ignored.
  Bytes longer = payload;
  longer.insert(longer.end(), {1, 2, 3, 4, 5, 6});
  EXPECT_TRUE(decodeSip(longer.data(), longer.size(), sip, &error)) << error;
  // Without the optional I/O bytes.
  EXPECT_TRUE(decodeSip(payload.data(), 26, sip, &error)) << error;
  EXPECT_FALSE(sip.has_io);
}

TEST(Protocol, ParserResynchronisesAfterGarbageDroppedBytesAndBadChecksums) {
  Bytes stream{0x13, 0x11, 0x0A, 0xFA, 0x00, 0xFA};  // garbage incl. a lone header byte
  const Bytes vel = commandPacket(cmd::kVel, 200);
  Bytes broken = kExampleSip;
  broken[10] ^= 0xFF;  // bad checksum
  Bytes dropped = kExampleSip;
  dropped.erase(dropped.begin() + 15);      // one byte lost
  Bytes bad_count{0xFA, 0xFB, 0xF0, 0x01};  // count 240 > 200
  for (const Bytes* b : std::vector<const Bytes*>{&vel, &broken, &dropped, &bad_count, &kExampleSip})
    stream.insert(stream.end(), b->begin(), b->end());
  PacketParser parser;
  // Feed byte by byte to exercise partial packets.
  std::vector<Bytes> got;
  Bytes payload;
  for (uint8_t b : stream) {
    parser.feed(&b, 1);
    while (parser.next(payload)) got.push_back(payload);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], payloadOf(vel));
  EXPECT_EQ(got[1], payloadOf(kExampleSip));
  EXPECT_EQ(parser.stats().packets, 2u);
  EXPECT_GE(parser.stats().checksum_errors, 2u);  // the broken and the shortened SIP
  EXPECT_GE(parser.stats().bad_counts, 1u);
  EXPECT_GT(parser.stats().skipped_bytes, 0u);
  EXPECT_LT(parser.buffered(), 3u);
}

TEST(Protocol, DecodeCommandArguments) {
  ClientCommand c;
  Bytes p = payloadOf(commandPacket(cmd::kVel, -200));
  ASSERT_TRUE(decodeCommand(p.data(), p.size(), c));
  EXPECT_EQ(c.number, cmd::kVel);
  EXPECT_EQ(c.arg, ClientCommand::Arg::kInt);
  EXPECT_EQ(c.value, -200);
  p = payloadOf(commandPacket(cmd::kOpen));
  ASSERT_TRUE(decodeCommand(p.data(), p.size(), c));
  EXPECT_EQ(c.arg, ClientCommand::Arg::kNone);
  p = payloadOf(commandPacket(42, std::string("hi")));
  ASSERT_TRUE(decodeCommand(p.data(), p.size(), c));
  EXPECT_EQ(c.text, "hi");
  std::string error;
  const Bytes bad{cmd::kVel, 0x3B, 0x01};
  EXPECT_FALSE(decodeCommand(bad.data(), bad.size(), c, &error));
  EXPECT_NE(error.find("truncated"), std::string::npos);
}

TEST(Odometry, FifteenBitWrapAround) {
  EXPECT_EQ(wrapDelta15(10, 0x7FF0), 0x1A);   // forward across the wrap
  EXPECT_EQ(wrapDelta15(0x7FF0, 10), -0x1A);  // backward across the wrap
  EXPECT_EQ(wrapDelta15(0x1000, 0), 0x1000);  // exactly the limit is no wrap
  EXPECT_EQ(wrapDelta15(0x1001, 0), 0x1001 - 0x8000);
  EXPECT_EQ(wrapDelta15(0, 0x1001), 0x8000 - 0x1001);
  EXPECT_EQ(wrapDelta15(0xFFFF, 0x7FFF), 0);  // bit 15 is ignored
}

TEST(Odometry, IntegratesAcrossTheWrapWithConversionFactors) {
  RobotParams p;
  OdometryIntegrator odo(p);
  odo.rebase(scanstop::Pose2D());
  Sip s;
  s.x = 0x7FF0;
  s.y = 100;
  odo.update(s);  // reference
  EXPECT_NEAR(odo.pose().x, 0.0, 1e-12);
  s.x = 0x0010;  // +0x20 units across the wrap
  odo.update(s);
  EXPECT_NEAR(odo.pose().x, 0x20 * 0.84e-3, 1e-9);
  EXPECT_NEAR(odo.pose().y, 0.0, 1e-12);
  // A full 27.5 m drive in steps of 0x0800 units wraps once and keeps counting.
  double expected = 0x20 * 0.84e-3;
  for (int i = 0; i < 16; ++i) {
    s.x = static_cast<uint16_t>((s.x + 0x0800) & 0x7FFF);
    odo.update(s);
    expected += 0x0800 * 0.84e-3;
  }
  EXPECT_NEAR(odo.pose().x, expected, 1e-9);
  EXPECT_GT(odo.pose().x, 27.5);
  // Heading: 1024 units = pi/2; wheel velocities 100 / 120 mm/s.
  s.th = 1024;
  s.left_vel = 100;
  s.right_vel = 120;
  odo.update(s);
  EXPECT_NEAR(odo.pose().yaw, 1024 * 0.001534, 1e-9);
  EXPECT_NEAR(odo.linearVelocity(), 0.110, 1e-12);
  EXPECT_NEAR(odo.angularVelocity(), 20 * 0.0056 / 2, 1e-12);
}

TEST(Odometry, RebaseKeepsTheOdomFrameContinuous) {
  OdometryIntegrator odo{RobotParams()};
  odo.rebase(scanstop::Pose2D(1.0, 2.0, M_PI / 2));
  Sip s;
  s.x = 5000;   // the robot's own counters after a restart are arbitrary
  s.th = 2048;  // pi
  odo.update(s);
  EXPECT_NEAR(odo.pose().x, 1.0, 1e-9);
  EXPECT_NEAR(odo.pose().y, 2.0, 1e-9);
  EXPECT_NEAR(odo.pose().yaw, M_PI / 2, 1e-9);
  // The robot drives 0.84 m along its own heading (pi in its frame) -> +y in odom.
  const double c = std::cos(2048 * 0.001534), sn = std::sin(2048 * 0.001534);
  s.x = static_cast<uint16_t>(5000 + std::lround(1000 * c));
  s.y = static_cast<uint16_t>(std::lround(1000 * sn) & 0x7FFF);
  odo.update(s);
  EXPECT_NEAR(odo.pose().x, 1.0, 2e-3);
  EXPECT_NEAR(odo.pose().y, 2.84, 2e-3);
}

TEST(Odometry, ParamsValidationNamesTheField) {
  RobotParams p;
  p.dist_conv_mm = 0.0;
  try {
    p.validate("robot/");
    FAIL() << "expected ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("robot/dist_conv"), std::string::npos) << e.what();
  }
}

}  // namespace
