// The one option parser of every tool (issue #22 class 7): strict numbers, ranges, --help, unknown
// options, and JSON that stays JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "scanstop_common/error.h"
#include "scanstop_common/options.h"

namespace scanstop {
namespace {

struct Parsed {
  int rc = -1;
  std::string out, err;
};

Parsed parse(const Options& opts, std::vector<const char*> args) {
  args.insert(args.begin(), "tool");
  std::ostringstream out, err;
  Parsed p;
  p.rc = opts.parse(static_cast<int>(args.size()), args.data(), out, err);
  p.out = out.str();
  p.err = err.str();
  return p;
}

TEST(Options, IntegerOverflowAndGarbageAreRefusedWithNameValueAndRange) {
  int iterations = 100;
  Options opts("tool", "usage: tool [--max-iterations N]");
  opts.integer("--max-iterations", iterations, 1, 100000);
  // std::stoi answered "stoi" for this one.
  Parsed p = parse(opts, {"--max-iterations", "99999999999"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("tool: --max-iterations 99999999999: not an integer in [1, 100000]"), std::string::npos)
      << p.err;
  EXPECT_NE(p.err.find("usage: tool"), std::string::npos) << p.err;
  for (const char* bad : {"12abc", "1.5", "", " 5", "0x10", "1e3", "0", "100001", "-5", "99999999999999999999999"}) {
    p = parse(opts, {"--max-iterations", bad});
    EXPECT_EQ(p.rc, 2) << bad;
    EXPECT_NE(p.err.find("not an integer in [1, 100000]"), std::string::npos) << bad << ": " << p.err;
  }
  EXPECT_EQ(iterations, 100) << "a refused value changes nothing";
  p = parse(opts, {"--max-iterations", "250"});
  EXPECT_EQ(p.rc, -1) << p.err;
  EXPECT_EQ(iterations, 250);

  size_t scans = 0;
  Options sizes("tool", "usage");
  sizes.integer("--scans", scans, size_t{0}, size_t{1000});
  EXPECT_EQ(parse(sizes, {"--scans", "-1"}).rc, 2);
  EXPECT_EQ(parse(sizes, {"--scans", "18446744073709551617"}).rc, 2);
  EXPECT_EQ(parse(sizes, {"--scans", "7"}).rc, -1);
  EXPECT_EQ(scans, 7u);
}

TEST(Options, RealsRefuseTrailingGarbageNaNInfAndOutOfRange) {
  double c_max = 0.5, voxel = 0.0, angle = 0.0;
  Options opts("tool", "usage");
  opts.real("--c-max", c_max, 0.001, 5.0)
      .real("--voxel", voxel, 0.0, 10.0)
      .real("--r-c-deg", angle, 0.0, 90.0, M_PI / 180);
  Parsed p = parse(opts, {"--c-max", "0.1abc"});  // ran silently with 0.1 before
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("--c-max 0.1abc: not a number in [0.001, 5]"), std::string::npos) << p.err;
  p = parse(opts, {"--voxel", "-1"});  // ran silently before
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("--voxel -1: not a number in [0, 10]"), std::string::npos) << p.err;
  for (const char* bad : {"nan", "NaN", "inf", "-inf", "1e999", "", "0,1", " 1", "abc"}) {
    p = parse(opts, {"--c-max", bad});
    EXPECT_EQ(p.rc, 2) << bad;
    EXPECT_NE(p.err.find("not a number in [0.001, 5]"), std::string::npos) << bad << ": " << p.err;
  }
  EXPECT_EQ(c_max, 0.5);
  EXPECT_EQ(parse(opts, {"--c-max", "0.25", "--voxel", "1e-2", "--r-c-deg", "90"}).rc, -1);
  EXPECT_EQ(c_max, 0.25);
  EXPECT_EQ(voxel, 0.01);
  EXPECT_NEAR(angle, M_PI / 2, 1e-12);
}

TEST(Options, ListsNameTheBadValue) {
  std::vector<double> init;
  Options opts("tool", "usage");
  opts.custom("--init", [&](const std::string& v) { init = parseRealListArg("--init", v, 4, -1e4, 1e4, "x,y,z,yaw"); });
  Parsed p = parse(opts, {"--init", "nan,0,0,0"});  // accepted before, and --json then printed bare nan
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("--init nan,0,0,0: value 1 ('nan') is not a number in [-10000, 10000] (expected x,y,z,yaw)"),
            std::string::npos)
      << p.err;
  p = parse(opts, {"--init", "1,2,3"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("expected x,y,z,yaw (4 comma-separated numbers), found 3 values"), std::string::npos) << p.err;
  EXPECT_EQ(parse(opts, {"--init", "1,2,3,1e5"}).rc, 2);
  EXPECT_TRUE(init.empty());
  EXPECT_EQ(parse(opts, {"--init", "-1,2.5,0,90"}).rc, -1);
  EXPECT_EQ(init, (std::vector<double>{-1, 2.5, 0, 90}));
}

TEST(Options, HelpAnywhereWinsAndAppliesNothing) {
  std::string map_dir;
  bool json = false;
  int applied = 0;
  Options opts("icp_replay", "usage: icp_replay MAP_DIR");
  opts.positional("MAP_DIR", map_dir).flag("--json", json).custom("--out", [&](const std::string&) { ++applied; });
  for (const char* help : {"--help", "-h"}) {
    // `icp_replay --help` created a folder named --help/scans before.
    Parsed p = parse(opts, {help});
    EXPECT_EQ(p.rc, 0) << help;
    EXPECT_EQ(p.out, "usage: icp_replay MAP_DIR\n");
    EXPECT_TRUE(p.err.empty());
    p = parse(opts, {"--out", "x", "--json", "--bogus", help});
    EXPECT_EQ(p.rc, 0) << "help wins over a bad option";
  }
  EXPECT_TRUE(map_dir.empty());
  EXPECT_FALSE(json);
  EXPECT_EQ(applied, 0);
}

TEST(Options, UnknownOptionsMissingValuesAndArgumentsAreNamed) {
  std::string in, out, mode = "3dof";
  Options opts("tool", "usage: tool IN OUT");
  opts.positional("IN", in).positional("OUT", out).choice("--mode", mode, {"3dof", "6dof"});
  Parsed p = parse(opts, {"a", "b", "--mdoe", "6dof"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("tool: unknown option --mdoe"), std::string::npos) << p.err;
  p = parse(opts, {"a", "b", "--mode"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("--mode needs a value"), std::string::npos) << p.err;
  p = parse(opts, {"a", "b", "--mode", "7dof"});
  EXPECT_NE(p.err.find("--mode 7dof: must be one of 3dof, 6dof"), std::string::npos) << p.err;
  p = parse(opts, {"a"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("OUT is required"), std::string::npos) << p.err;
  p = parse(opts, {"a", "b", "c"});
  EXPECT_EQ(p.rc, 2);
  EXPECT_NE(p.err.find("unexpected argument c"), std::string::npos) << p.err;
  EXPECT_EQ(parse(opts, {"a", "b", "--mode", "6dof"}).rc, -1);
  EXPECT_EQ(in, "a");
  EXPECT_EQ(out, "b");
  EXPECT_EQ(mode, "6dof");
}

TEST(Options, JsonNumbersAreNeverBareNanOrInf) {
  EXPECT_EQ(jsonNumber(std::nan("")), "null");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(jsonNumber(-std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(jsonNumber(0.5), "0.5");
  EXPECT_EQ(jsonNumber(-1e-12), "-1e-12");
  EXPECT_EQ(jsonString("a \"b\"\\\n\x01"), "\"a \\\"b\\\"\\\\\\n\\u0001\"");
}

}  // namespace
}  // namespace scanstop
