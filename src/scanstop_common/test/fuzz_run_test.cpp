// Runs each libFuzzer target of scanstop_common (STL, PLY, XYZ, PCD readers, map-directory loader) for a
// fixed number of inputs (fixed seed: deterministic) from a seed corpus of small valid files written
// here; fails on a crash, sanitizer report, leak, uncaught exception or timeout.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <string>

#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/fuzz_finding.h"

namespace scanstop {
namespace {

std::string le32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string f32(float v) { return std::string(reinterpret_cast<const char*>(&v), 4); }
std::string be32f(float v) {
  std::string s = f32(v);
  return std::string(s.rbegin(), s.rend());
}

std::string binaryStl() {
  std::string s(80, ' ');
  s += le32(1);
  for (float v : {0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) s += f32(v);
  return s + std::string(2, '\0');
}

std::string plyHeader(const std::string& format) {
  return "ply\nformat " + format +
         " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
         "property list uchar int vertex_indices\nend_header\n";
}

std::string binaryPly(bool big_endian) {
  std::string s = plyHeader(big_endian ? "binary_big_endian" : "binary_little_endian");
  const float v[3][6] = {{0, 0, 0, 0, 0, 1}, {1, 0, 0, 0, 0, 1}, {0, 1, 0, 0, 0, 1}};
  for (const auto& row : v)
    for (float x : row) s += big_endian ? be32f(x) : f32(x);
  s += '\3';
  for (uint32_t i : {0u, 1u, 2u}) {
    const std::string b = le32(i);
    s += big_endian ? std::string(b.rbegin(), b.rend()) : b;
  }
  return s;
}

const char* const kPcdAscii =
    "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n"
    "COUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3\nnan nan nan\n";

/// A binary_compressed PCD of one point (1, 2, 3): LZF data as a single literal run.
std::string compressedPcd() {
  const std::string raw = f32(1) + f32(2) + f32(3);
  const std::string lzf = std::string(1, static_cast<char>(raw.size() - 1)) + raw;
  return "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
         "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA binary_compressed\n" +
         le32(static_cast<uint32_t>(lzf.size())) + le32(static_cast<uint32_t>(raw.size())) + lzf;
}

/// A binary PCD written by our own writer (organized 2 x 2 with ranges).
std::string binaryPcd(const std::string& dir) {
  PointCloud c;
  c.points = {{1, 0, 0}, {0, 1, 0}, {NAN, NAN, NAN}, {0, 0, 2}};
  c.ranges = {1, 1, NAN, 2};
  c.width = 2;
  c.height = 2;
  writePcd(dir + "/tmp.pcd", c);
  const std::string data = readFile(dir + "/tmp.pcd");
  std::remove((dir + "/tmp.pcd").c_str());
  return data;
}

const char* const kPosesHeader =
    "index,file,stamp_s,map_x,map_y,map_yaw,odom_x,odom_y,odom_yaw,sensor_x,sensor_y,sensor_z,"
    "converged,iterations,correspondences,rms_m,overlap\n";

std::string mapDirSeed(const std::string& poses, const std::string& scan) {
  const uint16_t n = static_cast<uint16_t>(poses.size());
  return std::string(1, static_cast<char>(n & 0xff)) + std::string(1, static_cast<char>(n >> 8)) + poses + scan;
}

class CommonFuzz : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/common_fuzz_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
    ASSERT_EQ(mkdir((dir_ + "/corpus").c_str(), 0700), 0);
  }
  void seed(const std::string& name, const std::string& bytes) {
    std::ofstream(dir_ + "/corpus/" + name, std::ios::binary) << bytes;
  }
  /// Runs FUZZER_DIR/<name>_fuzzer on the seeds for a fixed number of inputs (-runs, fixed -seed: the
  /// same inputs on every machine, so a pass here is a pass in CI; a time limit would make the number,
  /// and so the result, depend on the machine's load; a run cut short by the cap tried a prefix of the
  /// same inputs). COMMON_FUZZ_SECONDS (default 35) caps the time of each target.
  void run(const std::string& name, long runs_wanted) {
    const char* env = std::getenv("COMMON_FUZZ_SECONDS");
    const int seconds = env ? std::atoi(env) : 35;
    const char* runs_env = std::getenv("COMMON_FUZZ_RUNS");  // e.g. 10x for a longer campaign
    if (runs_env) runs_wanted = std::atol(runs_env);
    const std::string log = dir_ + "/fuzz.log";
    const std::string command = std::string(FUZZER_DIR) + "/" + name + "_fuzzer -runs=" + std::to_string(runs_wanted) +
                                " -max_total_time=" + std::to_string(seconds) +
                                " -seed=1 -timeout=10 -rss_limit_mb=2048 -max_len=4096" + " -artifact_prefix=" + dir_ +
                                "/ " + dir_ + "/corpus > " + log + " 2>&1";
    const int status = std::system(command.c_str());
    std::ifstream in(log);
    const std::string output((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << name << "_fuzzer failed (artifacts in " << dir_ << "):\n"
        << fuzzFinding(output) << "--- the end of the log:\n"
        << output.substr(output.size() > 3000 ? output.size() - 3000 : 0);
    // libFuzzer ends with "Done N runs in S second(s)": the run must have exercised the target.
    const size_t done = output.rfind("Done ");
    ASSERT_NE(done, std::string::npos) << output;
    const long runs = std::atol(output.c_str() + done + 5);
    EXPECT_GE(runs, std::min(runs_wanted, 1000L)) << output.substr(done);
    std::cout << name << "_fuzzer: " << output.substr(done, output.find('\n', done) - done) << std::endl;
    if (!HasFailure()) {
      const int rc = std::system(("rm -rf " + dir_).c_str());
      (void)rc;
    }
  }
  std::string dir_;
};

TEST_F(CommonFuzz, StlReader) {
  seed("binary", binaryStl());
  seed("ascii",
       "solid t\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\n"
       "endfacet\nendsolid t\n");
  run("stl", 200000);
}

TEST_F(CommonFuzz, PlyReader) {
  seed("ascii", plyHeader("ascii") + "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  seed("le", binaryPly(false));
  seed("be", binaryPly(true));
  run("ply", 200000);
}

TEST_F(CommonFuzz, XyzReader) {
  seed("xyz3", "0 0 0\n1.5 -2 3e-2 # comment\n\n");
  seed("xyz6", "0 0 0 0 0 1\nnan 1 2 0 1 0\n");
  run("xyz", 200000);
}

TEST_F(CommonFuzz, PcdReader) {
  seed("ascii", kPcdAscii);
  seed("compressed", compressedPcd());
  seed("binary", binaryPcd(dir_));
  run("pcd", 200000);
}

TEST_F(CommonFuzz, MapDirectoryLoader) {
  const std::string poses = std::string(kPosesHeader) +
                            "0,scans/scan_0000.pcd,0,0,0,0,0,0,0,0,0,0.5,1,3,100,0.01,0.9\n"
                            "1,scans/scan_0001.pcd,40,1,2,1.5,1.1,2,1.5,0,0,0.5,0,7,90,0.02,0.8\n";
  seed("two_scans", mapDirSeed(poses, kPcdAscii));
  seed("binary_scan", mapDirSeed(poses, binaryPcd(dir_)));
  run("map_dir", 20000);
}

}  // namespace
}  // namespace scanstop
