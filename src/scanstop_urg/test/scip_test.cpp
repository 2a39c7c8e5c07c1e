// gtests of the SCIP 2.0 codec, the line splitter and reply reader, the stepper protocol and the
// device emulators, against the worked examples of PROTOCOL_FACTS.md part 1.
#include <gtest/gtest.h>

#include <map>

#include "scanstop_urg/emulator.h"
#include "scanstop_urg/platform.h"
#include "scanstop_urg/scip.h"

namespace scanstop {
namespace urg {
namespace {

Reply readReply(const std::string& bytes, const std::string& echo, bool kv = false) {
  LineSplitter splitter;
  ReplyReader reader(echo, kv);
  bool done = false;
  splitter.feed(bytes.data(), bytes.size(), [&](const std::string& line) {
    if (!done) done = reader.feedLine(line);
  });
  EXPECT_TRUE(done) << "incomplete reply: " << bytes;
  return reader.reply();
}

TEST(Scip, PrecomputedStatusSums) {
  // PROTOCOL_FACTS 1.2: 00P 99b 01Q 02R 03S 04T 05U 10Q 0Aa 0Bb 0Cc 0Dd 0Ee 0Ff
  for (const char* s :
       {"00P", "99b", "01Q", "02R", "03S", "04T", "05U", "10Q", "0Aa", "0Bb", "0Cc", "0Dd", "0Ee", "0Ff"}) {
    const std::string line(s);
    EXPECT_EQ(withSum(line.substr(0, 2)), line);
    EXPECT_TRUE(checkSum(line)) << line;
  }
  EXPECT_FALSE(checkSum("00Q"));
  EXPECT_FALSE(checkSum(""));
}

TEST(Scip, KeyValueSumLeavesOutTheSemicolon) {
  for (const char* s : {"DMIN:20;4", "AMAX:725;o", "SCAN:600;e"}) {
    const std::string line(s);
    EXPECT_EQ(scipSum(line.substr(0, line.size() - 2)), line.back()) << line;
    EXPECT_FALSE(checkSum(line, false)) << line;  // the sum does not cover the ';'
    EXPECT_TRUE(checkSum(line, true)) << line;
  }
}

TEST(Scip, ValueEncodingExamples) {
  EXPECT_EQ(encodeValue(1234, 2), "CB");
  EXPECT_EQ(encodeValue(5432, 3), "1Dh");
  EXPECT_EQ(encodeValue(16000000, 4), "m2@0");
  EXPECT_EQ(encodeValue(1000, 3), "0?X");
  EXPECT_EQ(encodeValue(5000, 4), "01>8");
  uint32_t v = 0;
  ASSERT_TRUE(decodeValue("0?X", &v));
  EXPECT_EQ(v, 15u * 64 + 40);
  EXPECT_EQ(v, 1000u);
  ASSERT_TRUE(decodeValue("CB", &v));
  EXPECT_EQ(v, 1234u);
  ASSERT_TRUE(decodeValue("1Dh", &v));
  EXPECT_EQ(v, 5432u);
  ASSERT_TRUE(decodeValue("m2@0", &v));
  EXPECT_EQ(v, 16000000u);
  EXPECT_FALSE(decodeValue("0/X", &v));  // '/' < 0x30
  EXPECT_FALSE(decodeValue("0pX", &v));  // 'p' > 0x6F
  EXPECT_FALSE(decodeValue("", &v));
  EXPECT_FALSE(decodeValue("00000", &v));
  EXPECT_THROW(encodeValue(4096, 2), std::invalid_argument);
  EXPECT_THROW(encodeValue(1u << 18, 3), std::invalid_argument);
  EXPECT_THROW(encodeValue(1, 5), std::invalid_argument);
  for (uint32_t x : {0u, 1u, 63u, 64u, 4095u, 262143u})
    for (int chars = 3; chars <= 4; ++chars) {
      ASSERT_TRUE(decodeValue(encodeValue(x, chars), &v));
      EXPECT_EQ(v, x);
    }
}

TEST(Scip, WorkedExampleGdReply) {
  // PROTOCOL_FACTS 1.7: GD0384038601 -> 1000, 1234, 5432 mm at 5000 ms.
  const std::string bytes = "GD0384038601\n00P\n01>8G\n0?X0CB1DhI\n\n";
  EXPECT_EQ(scipSum("0?X0CB1Dh"), 'I');
  EXPECT_EQ(withSum("01>8"), "01>8G");
  EXPECT_EQ(scanCommand(384, 386, 1), "GD0384038601");
  const Reply r = readReply(bytes, "GD0384038601");
  EXPECT_EQ(r.status(), "00");
  const ScanData d = decodeScanReply(r, 384, 386, 1);
  EXPECT_EQ(d.timestamp_ms, 5000u);
  ASSERT_EQ(d.values.size(), 3u);
  EXPECT_EQ(d.values[0], 1000u);
  EXPECT_EQ(d.values[1], 1234u);
  EXPECT_EQ(d.values[2], 5432u);
}

TEST(Scip, EmulatorAnswersTheWorkedExampleByteForByte) {
  const std::map<int, uint32_t> ranges = {{384, 1000}, {385, 1234}, {386, 5432}};
  UrgEmulator urg([&](int step) { return ranges.count(step) ? ranges.at(step) : 0u; });
  EXPECT_EQ(urg.handleLine("GD0384038601").bytes, "GD0384038601\nE\n\n");  // boots in SCIP 1.1
  EXPECT_EQ(urg.handleLine("SCIP2.0").bytes, "SCIP2.0\n0\n\n");
  EXPECT_EQ(urg.handleLine("GD0044072501").bytes, "GD0044072501\n10Q\n\n");  // laser off
  EXPECT_EQ(urg.handleLine("BM").bytes, "BM\n00P\n\n");
  EXPECT_EQ(urg.handleLine("BM").bytes, "BM\n02R\n\n");
  urg.setClockMs(5000);
  EXPECT_EQ(urg.handleLine("GD0384038601").bytes, "GD0384038601\n00P\n01>8G\n0?X0CB1DhI\n\n");
  EXPECT_EQ(urg.handleLine("GD0384038601;tag7").bytes, "GD0384038601;tag7\n00P\n01>8G\n0?X0CB1DhI\n\n");
  EXPECT_EQ(urg.handleLine("QT").bytes, "QT\n00P\n\n");
  EXPECT_EQ(urg.handleLine("GD0044072501").bytes, "GD0044072501\n10Q\n\n");
}

TEST(Scip, EmulatorStatusCodes) {
  UrgEmulator urg([](int) { return 1000u; });
  urg.handleLine("SCIP2.0");
  urg.handleLine("BM");
  EXPECT_EQ(urg.handleLine("GDx044072501").bytes, "GDx044072501\n01Q\n\n");
  EXPECT_EQ(urg.handleLine("GD0044x72501").bytes, "GD0044x72501\n02R\n\n");
  EXPECT_EQ(urg.handleLine("GD004407250x").bytes, "GD004407250x\n03S\n\n");
  EXPECT_EQ(urg.handleLine("GD0044080001").bytes, "GD0044080001\n04T\n\n");
  EXPECT_EQ(urg.handleLine("GD0100005001").bytes, "GD0100005001\n05U\n\n");
  EXPECT_EQ(urg.handleLine("GD0044").bytes, "GD0044\n0Cc\n\n");
  EXPECT_EQ(urg.handleLine("XX").bytes, "XX\n0Ee\n\n");
  EXPECT_EQ(urg.handleLine("TM0").bytes, "TM0\n00P\n\n");
  EXPECT_EQ(urg.handleLine("QT").bytes, "QT\n0Ee\n\n");  // in time-stamp mode (urg_c: send TM2)
  EXPECT_EQ(urg.handleLine("TM2").bytes, "TM2\n00P\n\n");
  EXPECT_EQ(urg.handleLine("BM;01234567890123456").bytes, "BM;01234567890123456\n0Gg\n\n");
  urg.powerCycle();
  EXPECT_EQ(urg.handleLine("QT").bytes, "QT\nE\n\n");
}

TEST(Scip, FullScanIs31LinesOf64AndOneOf62) {
  UrgEmulator urg([](int step) { return static_cast<uint32_t>(100 + step * 7); });
  urg.handleLine("SCIP2.0");
  urg.handleLine("BM");
  const std::string bytes = urg.handleLine("GD0044072501;x").bytes;
  const Reply r = readReply(bytes, "GD0044072501;x");
  ASSERT_EQ(r.data.size(), 1u + 32u);
  for (size_t i = 1; i <= 31; ++i) EXPECT_EQ(r.data[i].size(), 64u);
  EXPECT_EQ(r.data[32].size(), 62u);
  const ScanData d = decodeScanReply(r, 44, 725, 1);
  ASSERT_EQ(d.values.size(), 682u);
  for (int k = 0; k < 682; ++k) ASSERT_EQ(d.values[static_cast<size_t>(k)], static_cast<uint32_t>(100 + (44 + k) * 7));
  // Values that straddle two lines: value 21 covers characters 63..65.
  EXPECT_EQ(d.values[21], static_cast<uint32_t>(100 + 65 * 7));
}

TEST(Scip, MdStreamsUntilItsCountOrQt) {
  UrgEmulator urg([](int step) { return static_cast<uint32_t>(1000 + step); });
  urg.handleLine("SCIP2.0");
  EXPECT_EQ(urg.handleLine("MD0044072501002;s").bytes, "MD0044072501002;s\n00P\n\n");  // ack; laser on by itself
  ASSERT_TRUE(urg.streaming());
  for (const char* echo : {"MD0044072501001;s", "MD0044072501000;s"}) {
    const Reply r = readReply(urg.nextStreamScan().bytes, echo);
    EXPECT_EQ(r.status_line, "99b");
    ASSERT_EQ(r.data.size(), 33u);
    Reply as_gd = r;
    as_gd.status_line = "00P";
    EXPECT_EQ(decodeScanReply(as_gd, 44, 725, 1).values[0], 1044u);
  }
  EXPECT_FALSE(urg.streaming());
  EXPECT_FALSE(urg.laserOn());                                                     // off after the last scan
  EXPECT_EQ(urg.handleLine("MD0044072501000").bytes, "MD0044072501000\n00P\n\n");  // endless
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(urg.nextStreamScan().bytes.empty());
  EXPECT_EQ(urg.handleLine("QT").bytes, "QT\n00P\n\n");
  EXPECT_FALSE(urg.streaming());
  EXPECT_TRUE(urg.nextStreamScan().bytes.empty());
  EXPECT_EQ(urg.handleLine("MD0044072501x02").bytes, "MD0044072501x02\n06V\n\n");
  EXPECT_EQ(urg.handleLine("MD00440725010x2").bytes, "MD00440725010x2\n07W\n\n");
  EXPECT_EQ(urg.handleLine("MD004407250100").bytes, "MD004407250100\n0Cc\n\n");
}

TEST(Scip, ClusterReportsTheSmallestValidValue) {
  UrgEmulator urg([](int step) { return step == 101 ? 1u : static_cast<uint32_t>(3000 - step); });
  urg.handleLine("SCIP2.0");
  urg.handleLine("BM");
  const Reply r = readReply(urg.handleLine("GD0100010303").bytes, "GD0100010303");
  const ScanData d = decodeScanReply(r, 100, 103, 3);
  ASSERT_EQ(d.values.size(), 2u);
  EXPECT_EQ(d.values[0], 2898u);  // min(2900, code 1 ignored, 2898)
  EXPECT_EQ(d.values[1], 2897u);
}

TEST(Scip, VvPpIiRepliesParse) {
  UrgEmulator urg([](int) { return 1000u; });
  urg.handleLine("SCIP2.0");
  const Reply pp = readReply(urg.handleLine("PP;1").bytes, "PP;1", true);
  EXPECT_EQ(pp.status(), "00");
  std::map<std::string, std::string> m;
  for (const auto& kv : parseKeyValues(pp)) m[kv.first] = kv.second;
  EXPECT_EQ(m["DMIN"], "20");
  EXPECT_EQ(m["DMAX"], "5600");
  EXPECT_EQ(m["ARES"], "1024");
  EXPECT_EQ(m["AMIN"], "44");
  EXPECT_EQ(m["AMAX"], "725");
  EXPECT_EQ(m["AFRT"], "384");
  EXPECT_EQ(m["SCAN"], "600");
  const std::string bytes = urg.handleLine("PP").bytes;
  EXPECT_NE(bytes.find("\nDMIN:20;4\n"), std::string::npos);
  EXPECT_NE(bytes.find("\nAMAX:725;o\n"), std::string::npos);
  EXPECT_NE(bytes.find("\nSCAN:600;e\n"), std::string::npos);
  const Reply vv = readReply(urg.handleLine("VV").bytes, "VV", true);
  m.clear();
  for (const auto& kv : parseKeyValues(vv)) m[kv.first] = kv.second;
  EXPECT_EQ(m["PROT"], "SCIP 2.0");
  // Lenient VV: wrong sums (a wrong SERI sum, urg_c PR #4) still parse.
  const Reply odd = readReply("VV\n00P\nVEND:Hokuyo;x\nPROD:URG;!\nSERI:H1;Z\n\n", "VV", true);
  m.clear();
  for (const auto& kv : parseKeyValues(odd)) m[kv.first] = kv.second;
  EXPECT_EQ(m["SERI"], "H1");
}

TEST(Scip, ReaderSkipsStaleLinesUntilTheEcho) {
  // The tail of an earlier half-read scan and garbage come before the echo of our command.
  const std::string bytes = "0?X0CB1DhI\n\nGD0384038601;3\n00P\n\nXYZ\nGD0384038601;4\n00P\n01>8G\n0?X0CB1DhI\n\n";
  LineSplitter splitter;
  ReplyReader reader("GD0384038601;4");
  bool done = false;
  splitter.feed(bytes.data(), bytes.size(), [&](const std::string& l) {
    if (!done) done = reader.feedLine(l);
  });
  ASSERT_TRUE(done);
  EXPECT_EQ(reader.skippedLines(), 6u);
  EXPECT_EQ(decodeScanReply(reader.reply(), 384, 386, 1).values[2], 5432u);
}

TEST(Scip, ReaderRejectsBadSumsAndShapes) {
  auto feedAll = [](const std::string& bytes, const std::string& echo) {
    LineSplitter splitter;
    ReplyReader reader(echo);
    splitter.feed(bytes.data(), bytes.size(), [&](const std::string& l) { reader.feedLine(l); });
  };
  try {
    feedAll("GD0384038601\n00P\n01>8G\n0?X0CB1DhJ\n\n", "GD0384038601");
    FAIL() << "no error";
  } catch (const ScipError& e) {
    EXPECT_EQ(e.kind(), ScipError::Kind::kChecksum);
    EXPECT_NE(std::string(e.what()).find("data line 2"), std::string::npos) << e.what();
  }
  try {
    feedAll("GD0384038601\n00Q\n\n", "GD0384038601");
    FAIL() << "no error";
  } catch (const ScipError& e) {
    EXPECT_EQ(e.kind(), ScipError::Kind::kChecksum);
  }
  try {
    feedAll("GD0384038601\n0\x01P\n", "GD0384038601");
    FAIL() << "no error";
  } catch (const ScipError& e) {
    EXPECT_EQ(e.kind(), ScipError::Kind::kChecksum);
  }
  try {
    feedAll("GD0384038601\n00PX\n", "GD0384038601");
    FAIL() << "no error";
  } catch (const ScipError& e) {
    EXPECT_EQ(e.kind(), ScipError::Kind::kFormat);
  }
}

TEST(Scip, DecodeRejectsMalformedBlocks) {
  auto kindOf = [](const std::string& bytes, int first, int last) {
    try {
      decodeScanReply(readReply(bytes, bytes.substr(0, bytes.find('\n'))), first, last, 1);
    } catch (const ScipError& e) {
      return e.kind();
    }
    return ScipError::Kind::kDisconnected;  // "no error"
  };
  EXPECT_EQ(kindOf("GD0384038601\n00P\n01>8G\n\n", 384, 386), ScipError::Kind::kFormat);              // no data
  EXPECT_EQ(kindOf("GD0384038601\n00P\n0?X0CB1DhI\n\n", 384, 386), ScipError::Kind::kFormat);         // no time line
  EXPECT_EQ(kindOf("GD0384038701\n00P\n01>8G\n0?X0CB1DhI\n\n", 384, 387), ScipError::Kind::kFormat);  // short
  EXPECT_EQ(kindOf("GD0044072501\n10Q\n\n", 44, 725), ScipError::Kind::kStatus);
  EXPECT_EQ(kindOf("GD0044072501\nE\n\n", 44, 725), ScipError::Kind::kScip11);
  // A character outside 0x30..0x6F that still has a right sum.
  const std::string payload = "0?X0C~1Dh";
  EXPECT_EQ(kindOf("GD0384038601\n00P\n01>8G\n" + withSum(payload) + "\n\n", 384, 386), ScipError::Kind::kFormat);
  try {
    decodeScanReply(readReply("GD0044072501\n10Q\n\n", "GD0044072501"), 44, 725, 1);
  } catch (const ScipError& e) {
    EXPECT_NE(std::string(e.what()).find("laser is off"), std::string::npos) << e.what();
  }
}

TEST(Scip, LineSplitterHandlesCrLfPartialsAndGarbage) {
  LineSplitter s(16);
  std::vector<std::string> lines;
  auto add = [&](const std::string& l) { lines.push_back(l); };
  s.feed("AB", 2, add);
  EXPECT_TRUE(s.partial());
  s.feed("C\r\nD\n", 5, add);
  const std::string garbage(40, 'x');
  s.feed(garbage.data(), garbage.size(), add);
  s.feed("yy\nOK\n", 6, add);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[0], "ABC");
  EXPECT_EQ(lines[1], "D");
  EXPECT_EQ(lines[2], "OK");
  EXPECT_EQ(s.overflows(), 1u);
}

// Found by the SCIP fuzzer in CI: "MS...;tag\r\r\r\n" kept six CRs in the line, the emulator echoed
// them in every scan message, and the host's reader, cutting one CR, did not recognise its own echo.
TEST(Scip, LineSplitterDropsEveryCrBeforeTheLf) {
  LineSplitter s;
  std::vector<std::string> lines;
  const std::string in = "MS0010020003005;x00440S\r\r\r\r\r\r\r\r\nA\rB\r\n";
  s.feed(in.data(), in.size(), [&](const std::string& l) { lines.push_back(l); });
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "MS0010020003005;x00440S");
  EXPECT_EQ(lines[1], "A\rB");  // a CR inside the line stays
}

TEST(Scip, ErrorCodesAndStatusMeanings) {
  EXPECT_STREQ(errorCodeMeaning(1), "reflection too weak");
  EXPECT_STREQ(errorCodeMeaning(19), "step cannot be measured");
  EXPECT_STREQ(errorCodeMeaning(12), "other error");
  EXPECT_STREQ(errorCodeMeaning(20), "distance");
  EXPECT_EQ(statusMeaning("BM", "01"), "laser fault: the laser cannot be switched on");
  EXPECT_EQ(statusMeaning("GD", "10"), "the laser is off (BM needed)");
  EXPECT_EQ(statusMeaning("GD", "0E"), "undefined command");
}

TEST(Stepper, ProtocolLinesAndStates) {
  using namespace stepper;
  EXPECT_EQ(formatCommand("SC", "0050"), withSum("SC0050") + "\n");
  StepperEmulator e;
  auto ask = [&](const std::string& cmd, const std::string& params = "") {
    const std::string out = e.handleLine(withSum(cmd + params));
    EXPECT_EQ(out.back(), '\n');
    return parseReply(out.substr(0, out.size() - 1));
  };
  EXPECT_EQ(ask("ST").status, kNotConfigured);
  EXPECT_EQ(ask("SC", "0000").status, kBadParameter);
  EXPECT_EQ(ask("SC", "12").status, kBadParameter);
  EXPECT_EQ(ask("SC", "0004").status, kOk);
  EXPECT_EQ(ask("ST").status, kNotHomed);
  EXPECT_EQ(ask("ER").values, "01");
  EXPECT_EQ(ask("ER").values, "00");
  EXPECT_EQ(ask("HM").status, kOk);
  const stepper::Reply st = ask("ST");
  EXPECT_EQ(st.status, kOk);
  EXPECT_EQ(st.values, "0001");
  EXPECT_NEAR(e.angle(), M_PI / 4, 1e-12);
  EXPECT_EQ(ask("SS").values, "00010004100");
  e.injectStall(1);
  EXPECT_EQ(ask("ST").status, kStall);
  EXPECT_EQ(ask("SS").values, "00010004003");
  EXPECT_EQ(ask("HM").status, kOk);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(ask("ST").status, kOk);
  EXPECT_EQ(ask("ST").status, kEndOfTravel);
  EXPECT_EQ(ask("QQ").status, kUnknownCommand);
  EXPECT_EQ(e.handleLine("HM!"), formatReply("XX", kBadSum, ""));
  EXPECT_THROW(parseReply("ST000"), PlatformError);
  EXPECT_THROW(parseReply("ST000x"), PlatformError);
}

TEST(Faults, CorruptAndDropBreakTheReplyDetectably) {
  UrgEmulator urg([](int step) { return static_cast<uint32_t>(500 + step); });
  urg.handleLine("SCIP2.0");
  urg.handleLine("BM");
  const std::string clean = urg.handleLine("GD0044072501").bytes;
  FaultInjector f(3);
  f.corruptChecksums(1);
  std::string bad = clean;
  EXPECT_TRUE(f.apply(bad));
  EXPECT_EQ(bad.size(), clean.size());
  EXPECT_NE(bad, clean);
  std::string again = clean;
  EXPECT_FALSE(f.apply(again));  // only one reply was to be corrupted
  EXPECT_EQ(again, clean);
  LineSplitter s;
  ReplyReader r("GD0044072501");
  EXPECT_THROW(s.feed(bad.data(), bad.size(), [&](const std::string& l) { r.feedLine(l); }), ScipError);
  f.dropBytes(1, 3);
  std::string dropped = clean;
  EXPECT_TRUE(f.apply(dropped));
  EXPECT_EQ(dropped.size(), clean.size() - 3);
}

TEST(Scene, BoxRoomDistances) {
  BoxRoomScene room;
  room.robot_x = 0.0;
  room.robot_y = 0.0;
  room.robot_yaw = 0.0;
  room.dark_patch = false;
  room.validate();
  // Step 384 points straight up: ceiling at 2.5 m, scanner at 0.45 m.
  EXPECT_EQ(room.value(0.0, 384), 2050u);
  // Step 640 points along +x in plane 0: wall at 3 m; in plane pi/2 along +y: wall at 2.5 m.
  EXPECT_EQ(room.value(0.0, 640), 3000u);
  EXPECT_EQ(room.value(M_PI / 2, 640), 2500u);
  // Step 128 points along -x in plane 0.
  EXPECT_EQ(room.value(0.0, 128), 3000u);
  room.dark_patch = true;
  EXPECT_EQ(room.value(0.0, 600), 1u);     // 13.9 deg up: hits x = 3 m at z = 1.20 m, in the patch
  EXPECT_EQ(room.value(0.0, 590), 3147u);  // 17.6 deg up: z = 1.40 m, just above it
  room.robot_x = 5.0;
  EXPECT_THROW(room.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace urg
}  // namespace scanstop
