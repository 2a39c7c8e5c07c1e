// Bad input to the meshing pipeline (issue 9): output paths outside the allowed directory, absurd
// radii, voxels and coordinates, corrupt scan files of a map directory.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"
#include "scanstop_mesher/mesher.h"
#include "synthetic_room.h"

using namespace scanstop;
using namespace scanstop::mesher;

namespace {

struct Dir {
  std::string path;
  Dir() {
    char pattern[] = "/tmp/scanstop_mesher_bad_input_XXXXXX";
    path = mkdtemp(pattern);
  }
  ~Dir() { std::system(("rm -rf '" + path + "'").c_str()); }
};

/// The ConfigError message of resolveOutputPath, or "" when it was accepted.
std::string refusal(const std::string& path, const std::string& allowed) {
  try {
    resolveOutputPath(path, allowed);
    return "";
  } catch (const ConfigError& e) {
    return e.what();
  }
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(ResolveOutputPath, AcceptsPathsInsideTheDirectory) {
  Dir d;
  ASSERT_EQ(::mkdir((d.path + "/sub").c_str(), 0755), 0);
  EXPECT_EQ(resolveOutputPath(d.path + "/mesh.ply", d.path), d.path + "/mesh.ply");
  EXPECT_EQ(resolveOutputPath("mesh.stl", d.path), d.path + "/mesh.stl");
  EXPECT_EQ(resolveOutputPath("sub/../sub/./mesh.ply", d.path), d.path + "/sub/mesh.ply");
  EXPECT_EQ(resolveOutputPath(d.path + "//sub/mesh.ply", d.path + "/"), d.path + "/sub/mesh.ply");
}

TEST(ResolveOutputPath, RefusesDotDotEscapingTheRunDirectory) {
  Dir d;
  ASSERT_EQ(::mkdir((d.path + "/run").c_str(), 0755), 0);
  const std::string m = refusal(d.path + "/run/../mesh.ply", d.path + "/run");
  EXPECT_TRUE(has(m, "lies outside the output directory")) << m;
  EXPECT_TRUE(has(m, "/run/../mesh.ply")) << m;
  EXPECT_TRUE(has(refusal("../mesh.ply", d.path + "/run"), "outside")) << refusal("../mesh.ply", d.path + "/run");
  EXPECT_TRUE(has(refusal("../../../../../../../../../../tmp/x.ply", d.path + "/run"), "root"));
}

TEST(ResolveOutputPath, RefusesSystemDirectories) {
  Dir d;
  EXPECT_TRUE(has(refusal("/etc/mesh.ply", d.path), "outside")) << refusal("/etc/mesh.ply", d.path);
  EXPECT_TRUE(has(refusal("/etc/cron.d/x.stl", d.path), "outside"));
}

TEST(ResolveOutputPath, RefusesASymlinkOutOfTheDirectory) {
  Dir d;
  ASSERT_EQ(::symlink("/etc", (d.path + "/etc_link").c_str()), 0);
  EXPECT_TRUE(has(refusal(d.path + "/etc_link/mesh.ply", d.path), "outside"));
}

TEST(ResolveOutputPath, RefusesMissingDirectoriesWrongExtensionsDirectoriesAndNoAllowedDirectory) {
  Dir d;
  EXPECT_TRUE(has(refusal(d.path + "/nosuch/mesh.ply", d.path), "does not exist"));
  EXPECT_TRUE(has(refusal(d.path + "/mesh.obj", d.path), "must end in .stl or .ply"));
  EXPECT_TRUE(has(refusal("", d.path), "empty"));
  ASSERT_EQ(::mkdir((d.path + "/dir.ply").c_str(), 0755), 0);
  EXPECT_TRUE(has(refusal(d.path + "/dir.ply", d.path), "is a directory"));
  EXPECT_TRUE(has(refusal(d.path + "/mesh.ply", ""), "output_dir"));
  EXPECT_TRUE(has(refusal("mesh.ply", d.path + "/missing"), "output directory"));
}

TEST(PointsProblem, EmptyAndAbsurdCoordinates) {
  ScanPoints pts;
  EXPECT_TRUE(has(pointsProblem(pts, 1e4), "no finite points"));
  pts.points = {{0, 0, 0}, {1, 2, 3}};
  EXPECT_EQ(pointsProblem(pts, 1e4), "");
  pts.points.emplace_back(0.0f, 3e7f, 0.0f);
  EXPECT_TRUE(has(pointsProblem(pts, 1e4), "point 2")) << pointsProblem(pts, 1e4);
}

TEST(MesherConfig, RefusesNaNAbsurdAndTooManyRadiiAndVoxels) {
  const auto message = [](const MesherConfig& c) {
    try {
      c.validate();
      return std::string();
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
  };
  MesherConfig c;
  c.radii_m = {0.05, std::nan("")};
  EXPECT_TRUE(has(message(c), "radii_m[1]")) << message(c);
  c.radii_m = {0.05, 50.0};
  EXPECT_TRUE(has(message(c), "'radii_m[1]' = 50 m is out of range [0, 10 m]")) << message(c);
  c.radii_m = {-0.1};
  EXPECT_TRUE(has(message(c), "radii_m[0]")) << message(c);
  c.radii_m.assign(40, 0.0);
  for (size_t k = 0; k < c.radii_m.size(); ++k) c.radii_m[k] = 0.01 * (k + 1);
  EXPECT_TRUE(has(message(c), "40 radii")) << message(c);
  c = MesherConfig();
  c.voxel_m = std::nan("");
  EXPECT_TRUE(has(message(c), "voxel_m")) << message(c);
  c.voxel_m = 100.0;
  EXPECT_TRUE(has(message(c), "'voxel_m' = 100 m is out of range [0, 10 m]")) << message(c);
}

TEST(LoadMapDirectory, SkipsACorruptScanByNameWhenAskedAndRefusesWhenNoneIsLeft) {
  Dir d;
  const std::string dir = d.path + "/map";
  {
    MapDirectory map(dir);
    for (uint32_t s = 0; s < 3; ++s) {
      MapScanInfo info;
      info.index = s;
      info.sensor_origin = Eigen::Vector3d(0, 0, 0.45);
      PointCloud base;
      for (const auto& p : test::scanRoom(Eigen::Vector3f(0, 0, 0.45), 20, 60)) base.push_back(p);
      map.append(info, base);
    }
  }
  const size_t full = loadMapDirectory(dir).size();
  std::ofstream(dir + "/scans/scan_0001.pcd") << "garbage\n";
  EXPECT_THROW(loadMapDirectory(dir), IoError);  // strict without a list
  std::vector<std::string> skipped;
  const ScanPoints pts = loadMapDirectory(dir, &skipped);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_TRUE(has(skipped[0], dir + "/scans/scan_0001.pcd")) << skipped[0];
  EXPECT_EQ(pts.size(), full / 3 * 2);
  for (const auto v : pts.view) EXPECT_LT(v, pts.origins.size());
  std::ofstream(dir + "/scans/scan_0000.pcd") << "garbage\n";
  std::ofstream(dir + "/scans/scan_0002.pcd") << "";
  skipped.clear();
  try {
    loadMapDirectory(dir, &skipped);
    FAIL() << "no scan left";
  } catch (const IoError& e) {
    EXPECT_TRUE(has(e.what(), dir)) << e.what();
  }
  EXPECT_EQ(skipped.size(), 3u);
}
