// surface_accuracy on bad arguments and bad input (named, exit 2 / 1), and on a mesh, a cloud and a map
// directory of a small room whose distances are known (--json valid JSON).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <string>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/stl_io.h"
#include "test_rooms.h"

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& cmd) { return scanstop::test_util::runCommand(cmd); }

/// A 3 x 3 m room, interior [0, 3]^2 (the east wall's inner face at x = 3).
scanstop::TriangleMesh smallRoom() { return scanstop::test_util::squareRoom(3.0, 0.6); }

const std::string kTool = SURFACE_ACCURACY_EXE;
const std::string kStart = " --start 1.5,1.5,0";  // the map frame: the world moved by (1.5, 1.5)

}  // namespace

TEST(SurfaceAccuracyCli, BadArgumentsAndBadInputsAreNamed) {
  TempDir tmp("surface_accuracy_cli_test");
  const std::string world = tmp.path + "/small_room.stl";
  scanstop::writeStlBinary(world, smallRoom());
  CliRun r = run(kTool + " " + world + " " + tmp.path + "/missing.ply" + kStart);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/missing.ply: does not exist"), std::string::npos) << r.out;
  std::ofstream(tmp.path + "/mesh.obj") << "v 0 0 0\n";
  r = run(kTool + " " + world + " " + tmp.path + "/mesh.obj" + kStart);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/mesh.obj: unknown extension '.obj'"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + tmp.path + kStart);  // a directory, no poses.csv
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + ": a directory without poses.csv: not a map directory"), std::string::npos) << r.out;
  std::ofstream(tmp.path + "/broken.ply") << "ply\nformat ascii 1.0\nelement vertex 3\n";
  r = run(kTool + " " + world + " " + tmp.path + "/broken.ply" + kStart);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/broken.ply"), std::string::npos) << r.out;
  r = run(kTool + " " + tmp.path + "/missing.stl " + world + kStart);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find(tmp.path + "/missing.stl: the world file does not exist"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + world);  // no documented start pose for this world
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("no documented start pose for world 'small_room'"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + world + kStart + " --tolerance 0.06");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--tolerance 0.06 is larger than the surface cell 0.05"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + world + kStart + " --sample 1cm");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("--sample 1cm: not a number in [0.001, 1]"), std::string::npos) << r.out;
  r = run(kTool + " " + world);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.out.find("INPUT is required"), std::string::npos) << r.out;
  r = run(kTool + " --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_EQ(r.out.rfind("usage: surface_accuracy", 0), 0u) << r.out;
}

TEST(SurfaceAccuracyCli, AMeshACloudAndAMapDirectoryAreMeasuredInTheMapFrame) {
  TempDir tmp("surface_accuracy_cli_test");
  const std::string world = tmp.path + "/small_room.stl";
  scanstop::TriangleMesh room = smallRoom();
  scanstop::writeStlBinary(world, room);
  // The room itself in the map frame: exact, and all of the visible surface.
  for (Eigen::Vector3f& v : room.vertices) v -= Eigen::Vector3f(1.5f, 1.5f, 0.0f);
  scanstop::writeMesh(tmp.path + "/room_map.ply", room);
  CliRun r = run(kTool + " " + world + " " + tmp.path + "/room_map.ply" + kStart +
                 " --planes 50 --grid 1 --quiet --json | python3 -c 'import json, sys; d = json.load(sys.stdin); "
                 "print(\"parsed\", d[\"kind\"], d[\"triangles\"], d[\"surface_distance\"][\"max_m\"] < 1e-4, "
                 "d[\"coverage\"][\"share\"])'");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("parsed mesh " + std::to_string(room.faces.size()) + " True 1"), std::string::npos) << r.out;
  // A cloud 1 cm in front of the east wall (x = 3 in the world, 1.5 in the map frame).
  scanstop::PointCloud cloud;
  for (int i = 0; i < 5; ++i) cloud.points.emplace_back(1.49f, -0.5f + 0.25f * i, 1.0f);
  cloud.width = static_cast<uint32_t>(cloud.points.size());
  scanstop::writeCloud(tmp.path + "/wall.xyz", cloud);
  r = run(kTool + " " + world + " " + tmp.path + "/wall.xyz" + kStart + " --no-coverage");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("points to the world:         n 5: median 10.00 mm"), std::string::npos) << r.out;
  // The same points as one scan of a map directory, its map pose 2 cm further west.
  {
    scanstop::MapDirectory map(tmp.path + "/map");
    scanstop::MapScanInfo info;
    info.index = 0;
    info.map_pose = scanstop::Pose2D(-0.02, 0.0, 0.0);
    info.odom_pose = info.map_pose;
    map.append(info, cloud);
  }
  r = run(kTool + " " + world + " " + tmp.path + "/map" + kStart + " --no-coverage");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("(map)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("points: 5 from 1 scans"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("n 5: median 30.00 mm"), std::string::npos) << r.out;
}
