// Runs the libFuzzer target sip_fuzzer on a fixed number of inputs (400,000, fixed seed: the same inputs on
// every machine, so a pass here is a pass in CI; a time limit would make the number, and so the result,
// depend on the machine's load) from a seed corpus of the protocol's worked examples, at most 60 s
// (SIP_FUZZ_SECONDS; a capped run tried a prefix of the same inputs); SIP_FUZZ_RUNS overrides the count.
// Fails on a crash, sanitizer report, leak or timeout.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

#include "scanstop_common/fuzz_finding.h"
#include "scanstop_pioneer/p2os_protocol.h"

namespace {

using namespace scanstop::pioneer;

void writeSeed(const std::string& dir, const std::string& name, const std::vector<uint8_t>& bytes) {
  std::ofstream out(dir + "/" + name, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

TEST(SipFuzz, BoundedRunFindsNoCrash) {
  char tmpl[] = "/tmp/sip_fuzz_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::string dir = tmpl, corpus = dir + "/corpus";
  ASSERT_EQ(mkdir(corpus.c_str(), 0700), 0);
  Sip sip;
  sip.type = kSipMoving;
  sip.x = 1000;
  sip.y = 0x7FF0;
  sip.th = 1024;
  sip.sonar = {{0, 1866}, {1, 3731}};
  writeSeed(corpus, "sip", framePacket(encodeSip(sip)));
  writeSeed(corpus, "sync2", framePacket(encodeSync2Reply({"MyBot", "Pioneer", "p2dx"})));
  std::vector<uint8_t> mixed = commandPacket(cmd::kVel, -200);
  const std::vector<uint8_t> s = framePacket(encodeSip(sip));
  mixed.insert(mixed.end(), s.begin(), s.begin() + 10);
  mixed.insert(mixed.end(), s.begin(), s.end());
  writeSeed(corpus, "mixed", mixed);

  const char* env = std::getenv("SIP_FUZZ_SECONDS");
  const int seconds = env ? std::atoi(env) : 60;
  const char* runs_env = std::getenv("SIP_FUZZ_RUNS");
  const long runs_wanted = runs_env ? std::atol(runs_env) : 400000;
  const std::string log = dir + "/fuzz.log";
  const std::string command = std::string(SIP_FUZZER) + " -runs=" + std::to_string(runs_wanted) +
                              " -max_total_time=" + std::to_string(seconds) +
                              " -seed=1 -timeout=5 -rss_limit_mb=1024 -max_len=512 -artifact_prefix=" + dir + "/ " +
                              corpus + " > " + log + " 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(log);
  const std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
      << "sip_fuzzer failed (artifacts in " << dir << "):\n"
      << scanstop::fuzzFinding(output) << "--- the end of the log:\n"
      << output.substr(output.size() > 3000 ? output.size() - 3000 : 0);
  // libFuzzer ends with "Done N runs in S second(s)": the run must have exercised the parser.
  const size_t done = output.rfind("Done ");
  ASSERT_NE(done, std::string::npos) << output;
  const long runs = std::atol(output.c_str() + done + 5);
  EXPECT_GE(runs, std::min(runs_wanted, 10000L)) << output.substr(done);
  std::cout << "sip_fuzzer: " << output.substr(done, output.find('\n', done) - done) << std::endl;
  if (!HasFailure()) {
    const int rc = std::system(("rm -rf " + dir).c_str());
    (void)rc;
  }
}

}  // namespace
