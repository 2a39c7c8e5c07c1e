#include "scanstop_common/fuzz_finding.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "test_util.h"

namespace scanstop {
namespace {

TEST(FuzzFinding, NamesWhatWentWrongAndGivesTheInputInHex) {
  test::TempDir tmp;
  const std::string unit = tmp.file("crash-1");
  std::ofstream(unit, std::ios::binary) << std::string(
      "\x0c\x01"
      "ab",
      4);
  const std::string log =
      "INFO: Seed: 1\n#16001 REDUCE cov: 1697\nfuzz invariant violated: kept indices increase\n"
      "==1== ERROR: libFuzzer: deadly signal\n    #0 0x55 in abort\nSUMMARY: libFuzzer: deadly signal\n"
      "artifact_prefix='x/'; Test unit written to " +
      unit + "\n";
  const std::string found = fuzzFinding(log);
  EXPECT_NE(found.find("fuzz invariant violated: kept indices increase"), std::string::npos) << found;
  EXPECT_NE(found.find("SUMMARY: libFuzzer: deadly signal"), std::string::npos) << found;
  EXPECT_EQ(found.find("REDUCE"), std::string::npos) << found;  // progress lines are left out
  EXPECT_NE(found.find("the input (4 bytes, hex): 0c016162\n"), std::string::npos) << found;
  EXPECT_EQ(fuzzFinding("#1 INITED\nDone 20000 runs in 23 second(s)\n"), "");
  EXPECT_NE(fuzzFinding("Test unit written to /nonexistent/crash\n").find("/nonexistent/crash could not be read"),
            std::string::npos);
}

}  // namespace
}  // namespace scanstop
