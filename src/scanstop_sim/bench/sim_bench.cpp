// sim_bench: speed of the simulator's 3D scan against the practical limit of Embree on this machine.
//
//   sim_bench [--world FILE.stl]... [--pose x,y,yaw] [--planes N] [--repeat R] [--mixed-pixels]
//     With --mixed-pixels both simulated scans model mixed pixels (scanner/mixed_pixels, issue #20;
//     the bare Embree loop stays one ray per beam). For each world (default: the turtlebot3 house from the shared data
//     and worlds/room_10x8.stl), at the world's documented start pose (or --pose, world frame [m, m, rad]): times
//     Simulator::scan (perfect profile without the outlier filter = ray casting only; thesis profile with the filter =
//     everything the node does), a bare Embree loop (rtcIntersect1 per ray, no error model) over exactly the same rays,
//     each with one thread and with all OpenMP threads, and the in-process part of the service:
//     scan -> PointCloud2 (ros_conv::toMsg) -> TakeScan response serialized and deserialized with
//     ros::serialization. Prints medians (and minima) over R interleaved repetitions after one
//     warm-up (the variants take turns, so a shared machine's load hits them alike).
//
//   sim_bench --service [--planes N] [--repeat R]
//     Calls scanner/take_scan of a running sim_node R times and prints the wall-clock round trip
//     (scan, PointCloud2, serialization, TCPROS transfer, deserialization in the client).
#include <embree3/rtcore.h>
#include <omp.h>
#include <ros/ros.h>
#include <ros/serialization.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include "scanstop_common/options.h"
#include "scanstop_common/ros/msg_conversion.h"
#include "scanstop_msgs/TakeScan.h"
#include "scanstop_sim/simulator.h"
#include "scanstop_sim/world_builder.h"

namespace {

using Clock = std::chrono::steady_clock;
using scanstop::sim::ScannerConfig;
using scanstop::sim::SimConfig;
using scanstop::sim::Simulator;
using scanstop::sim::World;

struct Stat {
  double median_ms = 0.0, min_ms = 0.0;
};

/// Runs f once to warm up, then `repeat` times; median and minimum wall time [ms].
Stat timeIt(int repeat, const std::function<void()>& f) {
  f();
  std::vector<double> ms;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = Clock::now();
    f();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms.front()};
}

/// Like timeIt for several functions, interleaved (f0, f1, ..., f0, f1, ...) so that the load of
/// a shared machine affects all of them alike.
std::vector<Stat> timeInterleaved(int repeat, const std::vector<std::function<void()>>& fs) {
  for (const auto& f : fs) f();
  std::vector<std::vector<double>> ms(fs.size());
  for (int i = 0; i < repeat; ++i) {
    for (size_t k = 0; k < fs.size(); ++k) {
      const auto t0 = Clock::now();
      fs[k]();
      ms[k].push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    }
  }
  std::vector<Stat> out;
  for (auto& v : ms) {
    std::sort(v.begin(), v.end());
    out.push_back({v[v.size() / 2], v.front()});
  }
  return out;
}

constexpr const char* kUsage =
    "usage: sim_bench [--world FILE.stl]... [--pose x,y,yaw] [--planes N] [--repeat R] [--mixed-pixels]\n"
    "       sim_bench --service [--planes N] [--repeat R] [NAME:=VALUE ...]   (against a running sim_node)\n"
    "  --world   a world to scan, repeatable (default: turtlebot3_house and room_10x8)\n"
    "  --planes  planes per scan, [1, 2000] (default 400); --repeat  runs per figure, [1, 1000] (default 7)\n";

/// The documented start pose for a world file (by its base name), e.g. room_10x8 or turtlebot3_house.
scanstop::Pose2D startPoseFor(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  if (name.size() > 4 && name.compare(name.size() - 4, 4, ".stl") == 0) name.resize(name.size() - 4);
  return scanstop::sim::defaultStartPose(name);
}

/// Exactly the rays Simulator::scan casts at the true pose (world frame), computed before timing.
struct Rays {
  std::vector<Eigen::Vector3f> origins, directions;
  float max_range = 0.0f;
};

Rays makeRays(const ScannerConfig& sc, const scanstop::Pose2D& pose, int planes) {
  Rays r;
  const Eigen::Isometry3f T = pose.toIsometry3f();
  r.max_range = static_cast<float>(sc.max_range_m * 1.05);
  for (int p = 0; p < planes; ++p) {
    const Eigen::Vector3f o = T * sc.origin(p, planes);
    for (int b = 0; b < sc.beams(); ++b) {
      r.origins.push_back(o);
      r.directions.push_back(T.linear() * sc.direction(p, planes, b));
    }
  }
  return r;
}

/// The bare loop: one rtcIntersect1 per ray, the hit distance into `ranges`; returns the hit count.
size_t bareLoop(RTCScene scene, const Rays& rays, std::vector<float>& ranges) {
  const long n = static_cast<long>(rays.directions.size());
  ranges.resize(n);
  size_t hits = 0;
#pragma omp parallel for schedule(static, 1024) reduction(+ : hits)
  for (long i = 0; i < n; ++i) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = rays.origins[i].x();
    rh.ray.org_y = rays.origins[i].y();
    rh.ray.org_z = rays.origins[i].z();
    rh.ray.dir_x = rays.directions[i].x();
    rh.ray.dir_y = rays.directions[i].y();
    rh.ray.dir_z = rays.directions[i].z();
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = rays.max_range;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.flags = 0;
    rh.ray.time = 0.0f;
    rh.ray.id = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    const bool hit = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    ranges[i] = hit ? rh.ray.tfar : std::numeric_limits<float>::infinity();
    hits += hit ? 1 : 0;
  }
  return hits;
}

int benchWorlds(const std::vector<std::string>& worlds, const std::string& pose_text, int planes, int repeat,
                bool mixed_pixels) {
  const int max_threads = omp_get_max_threads();
  std::printf(
      "sim_bench: %d planes x 682 beams = %d rays per scan, median (min) of %d interleaved runs after a warm-up, "
      "OpenMP threads: 1 and %d, mixed pixels %s\n\n",
      planes, planes * 682, repeat, max_threads, mixed_pixels ? "on" : "off");
  std::printf("%-22s %3s %14s %14s %14s %14s %7s %7s\n", "world", "thr", "bare Embree", "scan perfect", "scan thesis",
              "+PointCloud2", "perf/", "thes/");
  std::printf("%-22s %3s %14s %14s %14s %14s %7s %7s\n", "", "", "[ms]", "(no filter)", "(+filter)", "+serialize",
              "bare", "bare");
  std::vector<std::string> notes;
  for (const std::string& path : worlds) {
    const scanstop::Pose2D start = pose_text.empty() ? startPoseFor(path) : scanstop::parsePose2D(pose_text);
    SimConfig perfect_cfg;
    perfect_cfg.errors = scanstop::sim::makeProfile("perfect");
    perfect_cfg.outlier_filter = false;
    SimConfig thesis_cfg;
    thesis_cfg.errors = scanstop::sim::makeProfile("thesis");
    perfect_cfg.scanner.mixed_pixels = thesis_cfg.scanner.mixed_pixels = mixed_pixels;
    Simulator perfect(World::load(path), perfect_cfg, start);
    Simulator thesis(World::load(path), thesis_cfg, start);
    const Rays rays = makeRays(perfect_cfg.scanner, start, planes);
    std::vector<float> work;
    size_t bare_hits = 0;
    uint32_t perfect_valid = 0, thesis_valid = 0, perfect_mixed = 0, perfect_candidates = 0;
    size_t bytes = 0;
    std::string name = path.substr(path.find_last_of('/') + 1);
    for (int threads : {1, max_threads}) {
      if (threads == 1 && max_threads == 1) continue;
      omp_set_num_threads(threads);
      auto serviceSide = [&] {
        // The node's part of the service: scan, PointCloud2, the TakeScan response on the wire and back.
        scanstop_msgs::TakeScan::Response res;
        const scanstop::sim::ScanOutput s = thesis.scan(planes);
        res.cloud = scanstop::ros_conv::toMsg(s.cloud, "base_link", ros::Time(1, 0));
        res.success = true;
        res.counts.raw_points = s.raw_points;
        res.counts.valid_points = s.valid_points;
        const ros::SerializedMessage m = ros::serialization::serializeServiceResponse(true, res);
        bytes = m.num_bytes;
        // serializeServiceResponse writes [ok: uint8][length: uint32][message]; the client reads the message.
        scanstop_msgs::TakeScan::Response back;
        ros::serialization::IStream in(m.buf.get() + 5, static_cast<uint32_t>(m.num_bytes - 5));
        ros::serialization::deserialize(in, back);
        if (back.cloud.data.size() != res.cloud.data.size()) {
          std::cerr << "sim_bench: deserialized cloud differs in size\n";
          std::exit(1);
        }
      };
      const std::vector<Stat> t =
          timeInterleaved(repeat, {[&] { bare_hits = bareLoop(perfect.world().scene(), rays, work); },
                                   [&] {
                                     const scanstop::sim::ScanOutput s = perfect.scan(planes);
                                     perfect_valid = s.valid_points;
                                     perfect_mixed = s.mixed_pixels;
                                     perfect_candidates = s.mixed_pixel_candidates;
                                   },
                                   [&] { thesis_valid = thesis.scan(planes).valid_points; }, serviceSide});
      const Stat &bare = t[0], &sp = t[1], &st = t[2], &ser = t[3];
      std::printf("%-22s %3d %7.2f (%4.1f) %7.2f (%4.1f) %7.2f (%4.1f) %7.2f (%4.1f) %7.2f %7.2f\n", name.c_str(),
                  threads, bare.median_ms, bare.min_ms, sp.median_ms, sp.min_ms, st.median_ms, st.min_ms, ser.median_ms,
                  ser.min_ms, sp.median_ms / bare.median_ms, st.median_ms / bare.median_ms);
    }
    // The parts of the service after the scan, each alone (all threads).
    {
      const scanstop::sim::ScanOutput s = thesis.scan(planes);
      scanstop_msgs::TakeScan::Response res;
      const Stat to_msg =
          timeIt(repeat, [&] { res.cloud = scanstop::ros_conv::toMsg(s.cloud, "base_link", ros::Time(1, 0)); });
      ros::SerializedMessage m;
      const Stat ser = timeIt(repeat, [&] { m = ros::serialization::serializeServiceResponse(true, res); });
      const Stat deser = timeIt(repeat, [&] {
        scanstop_msgs::TakeScan::Response back;
        ros::serialization::IStream in(m.buf.get() + 5, static_cast<uint32_t>(m.num_bytes - 5));
        ros::serialization::deserialize(in, back);
      });
      char parts[256];
      std::snprintf(parts, sizeof(parts), "%s: toMsg %.1f ms, serialize %.1f ms, deserialize %.1f ms (medians)",
                    name.c_str(), to_msg.median_ms, ser.median_ms, deser.median_ms);
      notes.push_back(parts);
    }
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "%s: %zu triangles, start %s; bare hits %zu, valid points perfect %u, thesis %u; "
                  "mixed pixels (perfect) %u of %u candidates; response %.1f MB",
                  name.c_str(), perfect.world().mesh().faces.size(), start.toString().c_str(), bare_hits, perfect_valid,
                  thesis_valid, perfect_mixed, perfect_candidates, bytes / 1e6);
    notes.push_back(buf);
  }
  std::printf("\n");
  for (const auto& n : notes) std::printf("%s\n", n.c_str());
  return 0;
}

int benchService(int planes, int repeat, int argc, char** argv) {
  ros::init(argc, argv, "sim_bench", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
  ros::NodeHandle nh;
  ros::ServiceClient client = nh.serviceClient<scanstop_msgs::TakeScan>("scanner/take_scan", true);
  if (!client.waitForExistence(ros::Duration(10.0))) {
    std::cerr << "sim_bench: service " << nh.resolveName("scanner/take_scan") << " not available within 10 s\n";
    return 1;
  }
  std::vector<double> ms;
  size_t bytes = 0;
  uint32_t valid = 0;
  for (int i = 0; i <= repeat; ++i) {
    scanstop_msgs::TakeScan srv;
    srv.request.planes = static_cast<uint16_t>(planes);
    const auto t0 = Clock::now();
    if (!client.call(srv) || !srv.response.success) {
      std::cerr << "sim_bench: take_scan failed: " << srv.response.message << "\n";
      return 1;
    }
    const double t = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (i > 0) ms.push_back(t);  // the first call is the warm-up (connection, allocation)
    bytes = srv.response.cloud.data.size();
    valid = srv.response.counts.valid_points;
  }
  std::sort(ms.begin(), ms.end());
  std::printf(
      "sim_bench --service: %s, %d planes: round trip median %.1f ms, min %.1f ms, max %.1f ms over %d calls "
      "(persistent connection, after a warm-up); cloud %.1f MB, %u valid points\n",
      nh.resolveName("scanner/take_scan").c_str(), planes, ms[ms.size() / 2], ms.front(), ms.back(), repeat,
      bytes / 1e6, valid);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  scanstop::sim::keepLargeBuffersMapped();  // as sim_node does
  std::vector<std::string> worlds;
  std::string pose_text;
  int planes = 400, repeat = 7;
  bool service = false, mixed_pixels = false;
  std::vector<std::string> remaps;
  scanstop::Options opts("sim_bench", kUsage);
  opts.custom("--world", [&](const std::string& v) { worlds.push_back(v); })
      .text("--pose", pose_text)
      .integer("--planes", planes, 1, 2000)
      .integer("--repeat", repeat, 1, 1000)
      .flag("--service", service)
      .flag("--mixed-pixels", mixed_pixels)
      .rest("NAME:=VALUE", remaps);
  if (const int rc = opts.parse(argc, argv); rc >= 0) return rc;
  std::vector<char*> ros_args{argv[0]};
  for (std::string& r : remaps) {
    if (r.find(":=") == std::string::npos) {
      std::cerr << "sim_bench: unexpected argument " << r << " (only ROS remappings NAME:=VALUE)\n" << kUsage;
      return scanstop::kExitUsage;
    }
    ros_args.push_back(&r[0]);
  }
  try {
    if (service) {
      int n = static_cast<int>(ros_args.size());
      return benchService(planes, repeat, n, ros_args.data());
    }
    if (worlds.empty())
      worlds = {SCANSTOP_SHARED_DATA_DIR "/worlds/turtlebot3_house.stl", SCANSTOP_WORLDS_DIR "/room_10x8.stl"};
    return benchWorlds(worlds, pose_text, planes, repeat, mixed_pixels);
  } catch (const std::exception& e) {
    std::cerr << "sim_bench: " << e.what() << "\n";
    return 1;
  }
}
