// libFuzzer target: the map-directory loader on arbitrary poses.csv content and an arbitrary scan file.
// Input: bytes 0-1 (little endian) are the length L of poses.csv, the next L bytes poses.csv, the rest
// scans/scan_0001.pcd (scans/scan_0000.pcd is a valid scan). The loader must never crash or throw; every
// problem names a file of the map; kept scans have increasing indices below nextIndex() and load (or fail
// with an IoError naming the file); appending at nextIndex() and reopening keeps every kept scan.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_util.h"
#include "scanstop_common/cloud_io.h"
#include "scanstop_common/error.h"
#include "scanstop_common/map_dir.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using scanstop::fuzz::check;
  static const std::string dir = scanstop::fuzz::scratchDir() + "/map";
  static const bool initialized = [] {
    scanstop::MapDirectory create(dir);
    scanstop::PointCloud cloud;
    cloud.push_back({1.0f, 0.0f, 0.0f});
    cloud.push_back({0.0f, 2.0f, 0.5f});
    scanstop::writeCloud(dir + "/scans/scan_0000.pcd", cloud);
    return true;
  }();
  (void)initialized;
  if (size < 2) return 0;
  const size_t poses = std::min<size_t>(data[0] | (static_cast<size_t>(data[1]) << 8), size - 2);
  // Each input is a map of its own: no journal of an earlier input's appends (it would restore their lines).
  std::remove((dir + "/poses_journal.csv").c_str());
  scanstop::fuzz::writeBytes(dir + "/poses.csv", data + 2, poses);
  scanstop::fuzz::writeBytes(dir + "/scans/scan_0001.pcd", data + 2 + poses, size - 2 - poses);
  scanstop::MapDirectory map(dir);  // must not throw: poses.csv is a regular, readable file
  for (const auto& p : map.problems())
    check(p.path.compare(0, dir.size(), dir) == 0, "a problem names a file of the map");
  for (size_t i = 0; i < map.size(); ++i) {
    check(map.scans()[i].index < map.nextIndex(), "kept indices are below nextIndex()");
    check(i == 0 || map.scans()[i - 1].index < map.scans()[i].index, "kept indices increase");
    try {
      const scanstop::PointCloud scan = map.loadScanInMap(i);
      check(scan.layoutProblem().empty(), "a loaded scan has a consistent layout");
    } catch (const scanstop::IoError& e) {
      check(std::string(e.what()).find(dir) == 0, "a scan error names the file");
    }
  }
  if (map.nextIndex() < 100) {  // appending (and reopening) stays cheap and the scratch directory small
    const size_t before = map.size();
    scanstop::MapScanInfo info;
    info.index = map.nextIndex();
    scanstop::PointCloud cloud;
    cloud.push_back({1.0f, 1.0f, 1.0f});
    map.append(info, cloud);
    const scanstop::MapDirectory again(dir);
    check(again.size() == before + 1, "append then reopen keeps every scan");
    check(again.scans().back().index == info.index, "the appended scan comes last");
    // (Past it, not necessarily to index + 1: a kept line may name the following file.)
    check(again.nextIndex() > info.index && map.nextIndex() > info.index, "nextIndex() moves past the appended scan");
    if (info.index > 1) std::remove((dir + "/" + map.scans().back().file).c_str());
  }
  return 0;
}
