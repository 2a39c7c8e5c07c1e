// fused_map_compare (the fused map against OctoMap, bench/) on bad arguments and bad input (named,
// exit 2 / 1), and on two perfect scans of a small room: both maps' surfaces measured against it.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <Eigen/Geometry>
#include <sstream>
#include <string>
#include <utility>

#include "scanstop_common/cli_test.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_common/stl_io.h"
#include "scanstop_sim/simulator.h"
#include "test_rooms.h"

namespace {

using scanstop::test_util::CliRun;
using scanstop::test_util::TempDir;

CliRun run(const std::string& cmd) { return scanstop::test_util::runCommand(cmd); }

/// A 3 x 3 m room, interior [0, 3]^2.
scanstop::TriangleMesh smallRoom() { return scanstop::test_util::squareRoom(3.0, 0.6); }

const std::string kTool = FUSED_MAP_COMPARE_EXE;

}  // namespace

TEST(FusedMapCompareCli, BadArgumentsAndBadInputsAreNamed) {
  TempDir tmp("fused_map_compare_cli_test");
  const std::string world = tmp.path + "/small_room.stl";
  scanstop::writeStlBinary(world, smallRoom());
  CliRun r = run(kTool + " " + world + " " + tmp.path + " --start 1.5,1.5,0 --voxel 0");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("--voxel 0"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + tmp.path + " --start 1.5,1.5,0 --bt map.txt");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("--bt map.txt: must end in .bt"), std::string::npos) << r.out;
  r = run(kTool + " " + world + " " + tmp.path + " --start 1.5,1.5,0 --no-coverage");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find(tmp.path + "/poses.csv: does not exist: not a map directory"), std::string::npos) << r.out;
  r = run(kTool + " " + tmp.path + "/none.stl " + tmp.path + " --start 1.5,1.5,0");
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("none.stl"), std::string::npos) << r.out;
  r = run(kTool + " --help");
  EXPECT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.rfind("usage: fused_map_compare", 0), 0u) << r.out;
}

// Two perfect 50-plane scans at their true poses (the map frame: the world moved by (1.5, 1.5)). The
// TSDF averages each surface between its voxels: its points lie within a millimetre of the walls;
// OctoMap's occupied leaves are voxel centres, a median quarter voxel (5 mm at 2 cm) off them.
TEST(FusedMapCompareCli, BothMapsOfASmallRoomAreMeasuredAgainstIt) {
  TempDir tmp("fused_map_compare_cli_test");
  const std::string world_path = tmp.path + "/small_room.stl";
  const scanstop::TriangleMesh room = smallRoom();
  scanstop::writeStlBinary(world_path, room);
  {
    scanstop::sim::SimConfig config;
    config.errors = scanstop::sim::makeProfile("perfect");
    const scanstop::Pose2D poses[] = {{1.0, 1.5, 0.0}, {2.0, 1.2, 2.0}};
    scanstop::sim::Simulator sim(scanstop::sim::World::fromMesh(room, "small_room"), config, poses[0]);
    scanstop::MapDirectory map(tmp.path + "/map");
    for (uint32_t i = 0; i < 2; ++i) {
      sim.reset(poses[i], -1);
      scanstop::MapScanInfo info;
      info.index = i;
      info.map_pose = scanstop::Pose2D(poses[i].x - 1.5, poses[i].y - 1.5, poses[i].yaw);
      info.odom_pose = info.map_pose;
      info.sensor_origin = Eigen::Vector3d(config.scanner.x_offset_m, 0.0, config.scanner.height_m);
      map.append(info, sim.scan(50).cloud);
    }
  }
  const CliRun r = run(kTool + " " + world_path + " " + tmp.path +
                       "/map --start 1.5,1.5,0 --no-coverage --quiet --json --bt " + tmp.path +
                       "/map.bt | python3 -c 'import json, sys; d = json.load(sys.stdin); m = d[\"methods\"]; "
                       "print(\"parsed\", d[\"scans\"], len(m), [x[\"name\"].split()[0] for x in m]); "
                       "[print(\"median\", x[\"name\"].split()[0], x[\"median_m\"], x[\"points\"] > 1000, "
                       "x[\"stray\"]) for x in m]'");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("parsed 2 3 ['OctoMap', 'TSDF', 'TSDF']"), std::string::npos) << r.out;
  size_t at = 0;
  int rows = 0;
  while ((at = r.out.find("median ", at)) != std::string::npos) {
    std::istringstream row(r.out.substr(at + 7));
    std::string name, many;
    double median = 0.0;
    int stray = -1;
    row >> name >> median >> many >> stray;
    EXPECT_EQ(many, "True") << r.out;
    EXPECT_EQ(stray, 0) << r.out;  // perfect scans: nothing 5 cm off
    if (name == "OctoMap")
      EXPECT_GT(median, 0.003) << r.out;
    else
      EXPECT_LT(median, 0.001) << r.out;
    ++rows;
    ++at;
  }
  EXPECT_EQ(rows, 3) << r.out;
  struct stat st;
  EXPECT_EQ(::stat((tmp.path + "/map.bt").c_str(), &st), 0);
  EXPECT_GT(st.st_size, 100);
}
