// The decimate_mesh command-line tool: a mesh file decimated as a user would, the JSON matching the
// file written, and bad arguments, inputs and outputs named.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_mesher/mesh_analysis.h"

using namespace scanstop;

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& args) {
  return scanstop::test_util::runCommand(std::string(DECIMATE_MESH_EXE) + " " + args);
}

double jsonValue(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return -1;
  return std::stod(json.substr(at + key.size() + 4));
}

/// A 1 x 1 m patch of 50 x 50 squares at z = 0, two triangles each.
TriangleMesh patch() {
  TriangleMesh m;
  const int n = 50;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i / 50.0f, j / 50.0f, 0.0f);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      m.faces.emplace_back(a, a + 1, a + n + 2);
      m.faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  return m;
}

}  // namespace

TEST(DecimateMeshCli, DecimatesAFileAndSaysWhatItDid) {
  TempDir tmp("decimate_mesh_cli_test");
  writeMesh(tmp.path + "/in.ply", patch());
  CliRun r = run(tmp.path + "/in.ply " + tmp.path + "/out.stl --json");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(jsonValue(r.out, "faces_before"), 5000);
  const TriangleMesh out = readMesh(tmp.path + "/out.stl");
  EXPECT_EQ(static_cast<double>(out.faces.size()), jsonValue(r.out, "faces_after"));
  EXPECT_LT(out.faces.size(), 500u) << "a flat patch keeps its 200 boundary vertices only";
  EXPECT_EQ(jsonValue(r.out, "locked_vertices"), 200);
  EXPECT_LE(jsonValue(r.out, "max_error_m"), 0.002);
  r = run(tmp.path + "/in.ply " + tmp.path + "/same.ply --error 0");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("decimated:    5000 triangles"), std::string::npos) << r.out;
  r = run(tmp.path + "/in.ply " + tmp.path + "/target.ply --error 0.1 --max-faces 1000");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_LE(readMesh(tmp.path + "/target.ply").faces.size(), 1000u);
}

TEST(DecimateMeshCli, BadArgumentsInputsAndOutputsAreNamed) {
  TempDir tmp("decimate_mesh_cli_test");
  writeMesh(tmp.path + "/in.ply", patch());
  CliRun r = run("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: decimate_mesh", 0), 0u) << r.out;
  r = run(tmp.path + "/in.ply " + tmp.path + "/out.ply --error 0.5");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--error 0.5: not a number in [0, 0.1]"), std::string::npos) << r.out;
  r = run(tmp.path + "/in.ply " + tmp.path + "/out.obj");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("out.obj: must end in .ply or .stl"), std::string::npos) << r.out;
  r = run(tmp.path + "/missing.ply " + tmp.path + "/out.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("missing.ply"), std::string::npos) << r.out;
  r = run(tmp.path + "/in.ply " + tmp.path + "/no/such/dir/out.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("no/such/dir/out.ply"), std::string::npos) << r.out;
  std::ofstream(tmp.path + "/points.ply")
      << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float "
         "y\nproperty float z\nend_header\n0 0 0\n";
  r = run(tmp.path + "/points.ply " + tmp.path + "/out.ply");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("has no triangles"), std::string::npos) << r.out;
}
