// The bpa_mesh command-line tool: counts as JSON, the files it writes, exit codes and messages.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/file_util.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/shared_data.h"

using namespace scanstop;

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

/// bpa_mesh with these arguments.
CliRun run(const std::string& args) { return scanstop::test_util::runCommand(std::string(BPA_MESH_EXE) + " " + args); }

/// The number after "key": in a flat JSON object (-1 when missing).
long jsonNumber(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return -1;
  return std::stol(json.substr(at + key.size() + 4));
}

}  // namespace

TEST(BpaMeshCli, MeshesACloudWithNormalsAndPrintsJson) {
  TempDir tmp("bpa_mesh_cli_test");
  const std::string in = sharedDataPath("clouds/bun0.pcd");  // 397 points with normals
  const CliRun r = run("'" + in + "' '" + tmp.path + "/bun0.stl' --radii 0.007,0.014 --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << "one line: " << r.out;
  EXPECT_EQ(jsonNumber(r.out, "input_points"), 397);
  EXPECT_EQ(jsonNumber(r.out, "points"), 397);
  const long triangles = jsonNumber(r.out, "triangles");
  EXPECT_GT(triangles, 300);
  EXPECT_EQ(jsonNumber(r.out, "nonmanifold_edges"), 0);
  EXPECT_EQ(jsonNumber(r.out, "nonmanifold_vertices"), 0);
  EXPECT_NE(r.out.find("\"radii_m\": [0.007,0.014]"), std::string::npos) << r.out;
  EXPECT_EQ(static_cast<long>(readMesh(tmp.path + "/bun0.stl").faces.size()), triangles);

  const CliRun text = run("'" + in + "' '" + tmp.path + "/bun0.ply'");  // automatic radii, PLY
  ASSERT_EQ(text.status, 0) << text.out;
  EXPECT_NE(text.out.find("non-manifold: 0 edges, 0 vertices"), std::string::npos) << text.out;
  const TriangleMesh ply = readMesh(tmp.path + "/bun0.ply");
  EXPECT_GT(ply.faces.size(), 300u);
  EXPECT_EQ(ply.normals.size(), ply.vertices.size());
}

TEST(BpaMeshCli, BadArgumentsAndFilesAreNamed) {
  TempDir tmp("bpa_mesh_cli_test");
  const std::string in = sharedDataPath("clouds/bun0.pcd");
  CliRun r = run("'" + in + "' " + tmp.path + "/x.ply --radii 0.01,abc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("'abc'"), std::string::npos) << r.out;
  r = run("'" + in + "' " + tmp.path + "/x.obj");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("x.obj"), std::string::npos) << r.out;
  r = run(tmp.path + "/missing.pcd " + tmp.path + "/x.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("missing.pcd"), std::string::npos) << r.out;
  r = run("'" + in + "' " + tmp.path + "/x.ply --voxel -1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("bpa_mesh: --voxel -1: not a number in [0, 10]"), std::string::npos) << r.out;
  r = run("'" + in + "'");
  EXPECT_EQ(r.status, 2);
}

// Issue #22: strict options and --help (class 7), an output in a missing directory named before any
// work (class 6; PCL said "Error during open!" without a path for .pcd), a map directory with a
// missing scan file refused by name unless --skip-bad (class 2).
TEST(BpaMeshCli, OptionsOutputsAndMapsFailFastByName) {
  TempDir tmp("bpa_mesh_cli_test");
  const std::string in = sharedDataPath("clouds/bun0.pcd");
  CliRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: bpa_mesh", 0), 0u) << r.out;
  r = run("'" + in + "' " + tmp.path + "/x.ply --voxel 0.01abc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--voxel 0.01abc: not a number in [0, 10]"), std::string::npos) << r.out;
  r = run("'" + in + "' " + tmp.path + "/x.ply --viewpoint 0,nan,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--viewpoint 0,nan,0: value 2 ('nan')"), std::string::npos) << r.out;
  r = run("'" + in + "' " + tmp.path + "/no_dir/x.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/no_dir/x.ply: cannot write: the directory " + tmp.path + "/no_dir does not exist"),
            std::string::npos)
      << r.out;
  r = run(tmp.path + " " + tmp.path + "/x.ply");  // a directory that is no map
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/poses.csv: does not exist"), std::string::npos) << r.out;

  const PointCloud bunny = readCloud(in);
  PointCloud points;
  for (const auto& p : bunny.points) points.push_back(p);
  {
    MapDirectory map(tmp.path + "/map");
    for (uint32_t i = 0; i < 2; ++i) {
      MapScanInfo info;
      info.index = i;
      info.sensor_origin = Eigen::Vector3d(0.0, 0.0, 0.5);
      map.append(info, points);
    }
  }
  ASSERT_EQ(std::remove((tmp.path + "/map/scans/scan_0001.pcd").c_str()), 0);
  r = run(tmp.path + "/map " + tmp.path + "/map.ply --radii 0.007,0.014");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/map/scans/scan_0001.pcd: no such file"), std::string::npos) << r.out;
  EXPECT_FALSE(std::ifstream(tmp.path + "/map.ply").good());
  r = run(tmp.path + "/map " + tmp.path + "/map.ply --radii 0.007,0.014 --skip-bad");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("bpa_mesh: warning: skipped: " + tmp.path + "/map/scans/scan_0001.pcd: no such file"),
            std::string::npos)
      << r.out;
  EXPECT_TRUE(std::ifstream(tmp.path + "/map.ply").good());
}
