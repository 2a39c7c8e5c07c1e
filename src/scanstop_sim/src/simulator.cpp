#include "scanstop_sim/simulator.h"

#include <errno.h>
#include <malloc.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "scanstop_common/config.h"
#include "scanstop_common/error.h"
#include "scanstop_sim/world_builder.h"

namespace scanstop {
namespace sim {

void keepLargeBuffersMapped() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);   // allocations up to 64 MB come from the heap ...
  mallopt(M_TRIM_THRESHOLD, 512 << 20);  // ... and freed memory stays there for the next scan
}

void SimConfig::validate(const std::string& profile_prefix) const {
  scanner.validate("scanner/");
  errors.sensor.validate(profile_prefix + "sensor/");
  errors.motion.validate(profile_prefix + "motion/", "motion/");
  requireInRange("robot_radius_m", robot_radius_m, 0.05, 2.0, "m");
  requireInRange("collision_step", collision_step_m, 0.0005, 0.1, "m");
  requireInRange("max_forward_m", max_forward_m, 0.1, 100.0, "m");
  requireInRange("max_rotate_rad", max_rotate_rad, 0.1, 4.0 * M_PI, "rad");
}

namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

constexpr int kMaxSurfacesPerBeam = 16;    ///< glass panes (faces) a beam passes at most
constexpr float kPassThroughStep = 1e-4f;  ///< [m] past a glass face before the next intersection

/// The surface that returns a beam: a diffuse or retroreflective surface returns it, an absorbing
/// one swallows it (no return), glass lets it through (or returns it with its reflect_probability,
/// drawn from `glass_rng` once per glass region the beam enters). Without materials: the first hit.
RayHit traceBeam(const World& world, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float tfar,
                 std::mt19937_64& glass_rng) {
  float tnear = 0.0f;
  const MaterialRegion* inside = nullptr;  // the glass region the beam entered last
  for (int k = 0; k < kMaxSurfacesPerBeam; ++k) {
    const RayHit h = world.intersect(o, d, tnear, tfar);
    if (!h.hit()) return h;
    const MaterialRegion* m = world.materialOf(h.prim);
    if (!m || m->material == Material::Diffuse || m->material == Material::Retroreflective) return h;
    if (m->material == Material::Absorbing) return RayHit();
    // Glass: the pane returns the beam with its probability once, where the beam enters it (not
    // again at its back face).
    if (m != inside && m->reflect_probability > 0.0 &&
        std::uniform_real_distribution<double>(0.0, 1.0)(glass_rng) < m->reflect_probability)
      return h;
    inside = m;
    tnear = h.t + kPassThroughStep;
  }
  return RayHit();
}

/// The noise-free range the sensor reads off a traced hit: its distance, short by the bias on a
/// retroreflective surface; +inf for no return.
float returnedRange(const World& world, const RayHit& h) {
  if (!h.hit()) return std::numeric_limits<float>::infinity();
  const MaterialRegion* m = world.materialOf(h.prim);
  if (m && m->material == Material::Retroreflective) return static_cast<float>(h.t - m->bias_m);
  return h.t;
}

}  // namespace

std::string checkScanPlanes(long planes) {
  if (planes == 50 || planes == 100 || planes == 200 || planes == 400) return "";
  return "planes = " + std::to_string(planes) + " is not one of 50, 100, 200, 400";
}

std::string checkRotation(double angle_rad, double max_rotate_rad) {
  if (std::isfinite(angle_rad) && std::abs(angle_rad) <= max_rotate_rad) return "";
  return "angle_rad = " + num(angle_rad) + " must be finite and within [-" + num(max_rotate_rad) + ", " +
         num(max_rotate_rad) + "] rad (parameter max_rotate_rad)";
}

std::string checkForward(double distance_m, double max_forward_m) {
  if (std::isfinite(distance_m) && std::abs(distance_m) <= max_forward_m) return "";
  return "distance_m = " + num(distance_m) + " must be finite and within [-" + num(max_forward_m) + ", " +
         num(max_forward_m) + "] m (parameter max_forward_m)";
}

std::string checkStartPose(const Pose2D& pose, const World& world, double robot_radius_m) {
  if (!pose.isFinite()) return "pose (" + num(pose.x) + ", " + num(pose.y) + ", " + num(pose.yaw) + ") is not finite";
  if (std::abs(pose.yaw) > 2.0 * M_PI) return "pose theta = " + num(pose.yaw) + " rad is outside [-2 pi, 2 pi]";
  const Eigen::Vector3f lo = world.minCorner(), hi = world.maxCorner();
  if (pose.x - robot_radius_m < lo.x() || pose.x + robot_radius_m > hi.x() || pose.y - robot_radius_m < lo.y() ||
      pose.y + robot_radius_m > hi.y())
    return "pose " + pose.toString() + " puts the robot (radius " + num(robot_radius_m) + " m) outside the world " +
           world.name() + " (x in [" + num(lo.x()) + ", " + num(hi.x()) + "], y in [" + num(lo.y()) + ", " +
           num(hi.y()) + "] m)";
  if (world.discCollides(Eigen::Vector2d(pose.x, pose.y), robot_radius_m))
    return "pose " + pose.toString() + " puts the robot (radius " + num(robot_radius_m) + " m) into an obstacle of " +
           world.name();
  return "";
}

std::unique_ptr<Simulator> makeSimulator(const std::string& world_path, const WorldOptions& world_options,
                                         const SimConfig& config, const std::string& start_text,
                                         const std::string& start_param, Pose2D* start_out) {
  // The world first: a missing file is the file's fault, not the (defaulted) start pose's.
  struct stat st;
  if (::stat(world_path.c_str(), &st) != 0)
    throw IoError(world_path, std::string("the world file does not exist (") + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) throw IoError(world_path, "the world file is not a regular file");
  World world = World::load(world_path, world_options);
  Pose2D start;
  std::string stem = world_path.substr(world_path.find_last_of('/') + 1);
  if (stem.rfind('.') != std::string::npos) stem = stem.substr(0, stem.rfind('.'));
  try {
    start = start_text.empty() ? defaultStartPose(stem) : parsePose2D(start_text);
  } catch (const std::exception& e) {
    throw ConfigError("parameter '" + start_param + "' = '" + start_text + "': " + e.what());
  }
  const std::string problem = checkStartPose(start, world, config.robot_radius_m);
  if (!problem.empty())
    throw ConfigError("parameter '" + start_param + "' = '" + start_text + "'" +
                      (start_text.empty() ? " (the world's documented start pose)" : "") + ": " + problem);
  if (start_out) *start_out = start;
  return std::make_unique<Simulator>(std::move(world), config, start);
}

Simulator::Simulator(World world, SimConfig config, const Pose2D& start_in_world)
    : world_(std::move(world)), config_(std::move(config)) {
  config_.validate();
  reset(start_in_world, static_cast<int64_t>(config_.seed));
}

void Simulator::reset(const Pose2D& start_in_world, int64_t seed) {
  const std::string problem = checkStartPose(start_in_world, world_, config_.robot_radius_m);
  if (!problem.empty()) throw std::invalid_argument(problem);
  start_ = start_in_world;
  true_world_ = start_in_world;
  odom_ = Pose2D();
  if (seed >= 0) {
    config_.seed = static_cast<uint64_t>(seed);
    rng_.seed(config_.seed);
    scan_counter_ = 0;
  }
}

std::string Simulator::saveState() const {
  std::ostringstream out;
  out.precision(17);
  const auto pose = [&](const char* name, const Pose2D& p) {
    out << name << ' ' << p.x << ' ' << p.y << ' ' << p.yaw << '\n';
  };
  out << "scanstop_sim_state 1\n";
  out << "world " << world_.name() << '\n';
  pose("start", start_);
  pose("true", true_world_);
  pose("odom", odom_);
  out << "clock " << clock_s_ << '\n';
  out << "scan_counter " << scan_counter_ << '\n';
  out << "seed " << config_.seed << '\n';
  out << "rng " << rng_ << '\n';
  for (const HiddenObstacle& h : hidden_) out << "hidden_obstacle " << h.x << ' ' << h.y << ' ' << h.radius << '\n';
  out << "end\n";
  return out.str();
}

void Simulator::restoreState(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != "scanstop_sim_state 1")
    throw std::invalid_argument("not a sim_node state (first line '" + line.substr(0, 40) +
                                "', expected 'scanstop_sim_state 1')");
  Pose2D start, truth, odom;
  double clock = -1.0;
  uint64_t counter = 0, seed = 0;
  std::mt19937_64 rng;
  std::string world;
  std::vector<HiddenObstacle> hidden;
  bool have[8] = {false, false, false, false, false, false, false, false};
  bool ended = false;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string key;
    ls >> key;
    const auto readPose = [&](Pose2D& p, int slot) {
      if (!(ls >> p.x >> p.y >> p.yaw) || !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.yaw))
        throw std::invalid_argument("field '" + key + "' is not three finite numbers: '" + line.substr(0, 80) + "'");
      have[slot] = true;
    };
    if (key == "world") {
      std::getline(ls >> std::ws, world);
      have[0] = true;
    } else if (key == "start") {
      readPose(start, 1);
    } else if (key == "true") {
      readPose(truth, 2);
    } else if (key == "odom") {
      readPose(odom, 3);
    } else if (key == "clock") {
      if (!(ls >> clock) || !std::isfinite(clock) || clock < 0.0)
        throw std::invalid_argument("field 'clock' is not a time >= 0");
      have[4] = true;
    } else if (key == "scan_counter") {
      if (!(ls >> counter)) throw std::invalid_argument("field 'scan_counter' is not a count");
      have[5] = true;
    } else if (key == "seed") {
      if (!(ls >> seed)) throw std::invalid_argument("field 'seed' is not a number");
      have[6] = true;
    } else if (key == "rng") {
      if (!(ls >> rng))
        throw std::invalid_argument("field 'rng' is not a random generator state of 312 numbers (truncated file?)");
      have[7] = true;
    } else if (key == "hidden_obstacle") {
      HiddenObstacle h;
      if (!(ls >> h.x >> h.y >> h.radius) || !std::isfinite(h.x) || !std::isfinite(h.y) ||
          !(h.radius > 0.0 && h.radius <= 2.0))
        throw std::invalid_argument("field 'hidden_obstacle' is not x y radius (finite, radius in (0, 2] m): '" +
                                    line.substr(0, 80) + "'");
      hidden.push_back(h);
    } else if (key == "end") {
      ended = true;
      break;
    } else if (!key.empty()) {
      throw std::invalid_argument("unknown field '" + key + "'");
    }
  }
  static const char* const names[8] = {"world", "start", "true", "odom", "clock", "scan_counter", "seed", "rng"};
  for (int i = 0; i < 8; ++i)
    if (!have[i]) throw std::invalid_argument(std::string("field '") + names[i] + "' is missing (truncated file?)");
  if (!ended) throw std::invalid_argument("the 'end' line is missing (truncated file?)");
  const auto stemOf = [](std::string name) {
    name = name.substr(name.find_last_of('/') + 1);
    return name.rfind('.') == std::string::npos ? name : name.substr(0, name.rfind('.'));
  };
  if (stemOf(world) != stemOf(world_.name()))
    throw StateOfAnotherWorld("the state is of world '" + world + "', this simulation runs '" + world_.name() + "'");
  for (const Pose2D* p : {&start, &truth}) {
    const std::string problem = checkStartPose(*p, world_, config_.robot_radius_m);
    if (!problem.empty()) throw std::invalid_argument(problem);
  }
  start_ = start;
  true_world_ = truth;
  odom_ = odom;
  clock_s_ = clock;
  scan_counter_ = counter;
  config_.seed = seed;
  rng_ = rng;
  hidden_ = hidden;
}

void Simulator::addHiddenObstacle(const HiddenObstacle& h) {
  if (!std::isfinite(h.x) || !std::isfinite(h.y))
    throw std::invalid_argument("hidden obstacle centre (" + num(h.x) + ", " + num(h.y) + ") is not finite");
  if (!(h.radius > 0.0 && h.radius <= 2.0))
    throw std::invalid_argument("hidden obstacle radius " + num(h.radius) + " m is outside (0, 2] m");
  const double d = std::hypot(h.x - true_world_.x, h.y - true_world_.y);
  if (d <= h.radius + config_.robot_radius_m)
    throw std::invalid_argument("hidden obstacle at (" + num(h.x) + ", " + num(h.y) + ") radius " + num(h.radius) +
                                " m would touch the robot where it stands (" + num(d) + " m from its centre)");
  hidden_.push_back(h);
}

bool Simulator::bodyCollides(const Eigen::Vector2d& p) const {
  if (world_.discCollides(p, config_.robot_radius_m)) return true;
  for (const HiddenObstacle& h : hidden_)
    if ((p - Eigen::Vector2d(h.x, h.y)).norm() <= h.radius + config_.robot_radius_m) return true;
  return false;
}

double Simulator::bodyClearance(const Eigen::Vector2d& p) const {
  const double r = config_.robot_radius_m;
  double c = std::max(0.0, world_.clearanceWithin(p, r + kClearanceRange) - r);
  for (const HiddenObstacle& h : hidden_)
    c = std::min(c, std::max(0.0, (p - Eigen::Vector2d(h.x, h.y)).norm() - h.radius - r));
  return c;
}

ScanOutput Simulator::scan(int planes) {
  if (planes < 1 || planes > 2000)
    throw std::invalid_argument("planes must be in [1, 2000], got " + std::to_string(planes));
  const ScannerConfig& sc = config_.scanner;
  const int beams = sc.beams();
  ScanOutput out;
  out.raw_points = static_cast<uint32_t>(planes * beams);
  PointCloud& cloud = out.cloud;
  cloud.width = static_cast<uint32_t>(beams);
  cloud.height = static_cast<uint32_t>(planes);
  cloud.points.assign(static_cast<size_t>(planes) * beams,
                      Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  cloud.ranges.assign(cloud.points.size(), std::numeric_limits<float>::quiet_NaN());

  // Which planes are lost in transmission (drawn up front so the result does not depend on threads).
  std::vector<uint8_t> lost(planes, 0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (int p = 0; p < planes; ++p) lost[p] = u01(rng_) < config_.errors.sensor.p_plane_loss ? 1 : 0;
  const uint64_t scan_seed = rng_();
  ++scan_counter_;

  const Eigen::Isometry3f T_world_base = true_world_.toIsometry3f();
  const Eigen::Matrix3f R_world_base = T_world_base.linear();
  const float tfar = static_cast<float>(sc.max_range_m * 1.05);
  // The beam angles within a plane are the same in every plane: their sines and cosines once per
  // scan (ScannerConfig::direction's formula, so the directions are bit for bit the same).
  std::vector<double> beam_sin(beams), beam_cos(beams);
  for (int b = 0; b < beams; ++b) {
    const double theta = (sc.first_step + b - sc.front_step) * 2.0 * M_PI / sc.steps_per_turn;
    beam_sin[b] = std::sin(theta);
    beam_cos[b] = std::cos(theta);
  }
  std::vector<double> plane_cos(planes), plane_sin(planes);
  std::vector<Eigen::Vector3f> origin_base(planes), origin_world(planes);
  for (int p = 0; p < planes; ++p) {
    const double phi = M_PI * p / planes;
    plane_cos[p] = std::cos(phi);
    plane_sin[p] = std::sin(phi);
    origin_base[p] = sc.origin(p, planes);
    origin_world[p] = T_world_base * origin_base[p];
  }
  const auto dirBase = [&](int p, int b) {
    return Eigen::Vector3f(static_cast<float>(beam_sin[b] * plane_cos[p]),
                           static_cast<float>(beam_sin[b] * plane_sin[p]), static_cast<float>(beam_cos[b]));
  };
  // Random streams per plane, independent of the thread that runs it: the range noise (as before
  // materials existed), glass reflections of the centre rays, those of mixed-pixel sub-rays.
  const auto planeRng = [&](uint64_t salt, int p) {
    return std::mt19937_64(scan_seed ^ (salt * static_cast<uint64_t>(p + 1)));
  };
  constexpr uint64_t kNoiseSalt = 0x9E3779B97F4A7C15ull, kGlassSalt = 0xD1B54A32D192ED03ull,
                     kSubRaySalt = 0x8CB92BA72F3D8DD7ull;
  const SensorNoiseConfig& noise = config_.errors.sensor;
  const auto store = [&](int p, int b, float r) {
    if (!std::isfinite(r)) return;
    const size_t i = static_cast<size_t>(p) * beams + b;
    cloud.ranges[i] = r;
    cloud.points[i] = origin_base[p] + r * dirBase(p, b);
  };

  if (!sc.mixed_pixels) {
#pragma omp parallel for schedule(dynamic, 4)
    for (int p = 0; p < planes; ++p) {
      if (lost[p]) continue;
      std::mt19937_64 rng = planeRng(kNoiseSalt, p), glass_rng = planeRng(kGlassSalt, p);
      std::normal_distribution<double> standard_normal(0.0, 1.0);
      for (int b = 0; b < beams; ++b) {
        const Eigen::Vector3f d_world = R_world_base * dirBase(p, b);
        const float hit = returnedRange(world_, traceBeam(world_, origin_world[p], d_world, tfar, glass_rng));
        store(p, b, sampleRange(noise, sc, hit, rng, standard_normal));
      }
    }
  } else {
    // Pass 1: the centre ray of every beam. Pass 2: beams whose neighbours (in the plane and in
    // the planes beside it) lie off their surface's plane get sub-rays over their footprint.
    std::vector<RayHit> hits(static_cast<size_t>(planes) * beams);
    std::vector<Eigen::Vector3f> hit_points(hits.size());  // world frame; meaningful where hits[i].hit()
#pragma omp parallel for schedule(dynamic, 4)
    for (int p = 0; p < planes; ++p) {
      if (lost[p]) continue;
      std::mt19937_64 glass_rng = planeRng(kGlassSalt, p);
      for (int b = 0; b < beams; ++b) {
        const size_t i = static_cast<size_t>(p) * beams + b;
        const Eigen::Vector3f d_world = R_world_base * dirBase(p, b);
        hits[i] = traceBeam(world_, origin_world[p], d_world, tfar, glass_rng);
        hit_points[i] = origin_world[p] + hits[i].t * d_world;
      }
    }
    const float threshold = static_cast<float>(sc.mixed_pixel_threshold_m);
    const int n = sc.mixed_pixel_samples;
    uint32_t mixed = 0, candidates = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : mixed, candidates)
    for (int p = 0; p < planes; ++p) {
      if (lost[p]) continue;
      std::mt19937_64 rng = planeRng(kNoiseSalt, p), sub_rng = planeRng(kSubRaySalt, p);
      std::normal_distribution<double> standard_normal(0.0, 1.0);
      for (int b = 0; b < beams; ++b) {
        const RayHit& c = hits[static_cast<size_t>(p) * beams + b];
        const Eigen::Vector3f& c_point = hit_points[static_cast<size_t>(p) * beams + b];
        // Another surface than the centre's: a return where it has none (or the reverse), or a
        // point more than the threshold off its plane (a plane seen at grazing incidence is one surface).
        const auto otherSurface = [&](const RayHit& h, const Eigen::Vector3f& point) {
          if (h.hit() != c.hit()) return true;
          return h.hit() && std::abs((point - c_point).dot(world_.faceNormal(c.prim))) > threshold;
        };
        bool candidate = false;
        const int nq[4] = {p, p, p - 1, p + 1}, nb[4] = {b - 1, b + 1, b, b};
        for (int k = 0; k < 4 && !candidate; ++k) {
          if (nq[k] < 0 || nq[k] >= planes || nb[k] < 0 || nb[k] >= beams || lost[nq[k]]) continue;
          const size_t i = static_cast<size_t>(nq[k]) * beams + nb[k];
          candidate = otherSurface(hits[i], hit_points[i]);
        }
        float hit = returnedRange(world_, c);
        if (candidate) {
          ++candidates;
          // n x n sub-rays over the square footprint (angular offsets in the plane and across it).
          const Eigen::Vector3f d = dirBase(p, b);
          const Eigen::Vector3f t_in(static_cast<float>(beam_cos[b] * plane_cos[p]),
                                     static_cast<float>(beam_cos[b] * plane_sin[p]), static_cast<float>(-beam_sin[b]));
          const Eigen::Vector3f t_across(static_cast<float>(-plane_sin[p]), static_cast<float>(plane_cos[p]), 0.0f);
          bool step = false;
          double weighted = 0.0, weights = 0.0;
          const auto subRay = [&](int i, int j) {
            const double a = std::tan(((i + 0.5) / n - 0.5) * sc.beam_divergence_rad);
            const double e = std::tan(((j + 0.5) / n - 0.5) * sc.beam_divergence_rad);
            const Eigen::Vector3f sub =
                R_world_base * (d + static_cast<float>(a) * t_in + static_cast<float>(e) * t_across).normalized();
            const RayHit h = traceBeam(world_, origin_world[p], sub, tfar, sub_rng);
            step = step || otherSurface(h, origin_world[p] + h.t * sub);
            if (!h.hit()) return;
            // Each sub-ray stands for an equal share of the footprint; the power a surface
            // returns falls with the square of its distance.
            const double w = 1.0 / (static_cast<double>(h.t) * h.t);
            weighted += w * returnedRange(world_, h);
            weights += w;
          };
          // The footprint's four corners first: a straight edge through the footprint puts at
          // least one corner on another surface than the centre's; when none is, the other
          // sub-rays are not cast (an object narrower than the corners' spacing that lies between
          // them is missed, like one between two beams).
          const auto corner = [n](int i, int j) { return (i == 0 || i == n - 1) && (j == 0 || j == n - 1); };
          for (const int i : {0, n - 1})
            for (const int j : {0, n - 1}) subRay(i, j);
          if (step)
            for (int i = 0; i < n; ++i)
              for (int j = 0; j < n; ++j)
                if (!corner(i, j)) subRay(i, j);
          if (step) {
            hit = weights > 0.0 ? static_cast<float>(weighted / weights) : std::numeric_limits<float>::infinity();
            ++mixed;
          }
        }
        store(p, b, sampleRange(noise, sc, hit, rng, standard_normal));
      }
    }
    out.mixed_pixels = mixed;
    out.mixed_pixel_candidates = candidates;
  }
  for (int p = 0; p < planes; ++p) out.planes_dropped += lost[p];
  if (config_.outlier_filter) out.outliers_removed = static_cast<uint32_t>(filterOutliers(cloud));
  out.valid_points = static_cast<uint32_t>(cloud.countFinite());
  out.duration_s = planes * sc.plane_time_s;
  clock_s_ += out.duration_s;
  return out;
}

MotionOutput Simulator::forward(double distance_m) {
  const std::string problem = checkForward(distance_m, config_.max_forward_m);
  if (!problem.empty()) throw std::invalid_argument(problem);
  MotionOutput out;
  const ForwardSample f = sampleForward(config_.errors.motion, distance_m, rng_);
  const double length = std::abs(f.true_length_m);
  const double sign = f.true_length_m < 0 ? -1.0 : 1.0;
  const Pose2D before = true_world_;
  double travelled = length;
  const auto clearanceAt = [this](const Pose2D& p) { return bodyClearance(Eigen::Vector2d(p.x, p.y)); };
  out.min_clearance_m = clearanceAt(before);
  for (double s = config_.collision_step_m; s < length + config_.collision_step_m; s += config_.collision_step_m) {
    const double t = std::min(s, length);
    const Pose2D p = before * f.along(sign * t);
    if (bodyCollides(Eigen::Vector2d(p.x, p.y))) {
      travelled = std::max(0.0, t - config_.collision_step_m);  // the last pose without contact
      out.collision = true;
      out.min_clearance_m = 0.0;
      break;
    }
    out.min_clearance_m = std::min(out.min_clearance_m, clearanceAt(p));
  }
  true_world_ = before * f.along(sign * travelled);
  if (!out.collision) true_world_ = true_world_ * Pose2D(0, 0, f.finish_angle_rad);
  // Odometry believes the robot drove straight; it measures the commanded distance scaled by how
  // much of the true path was driven.
  const double fraction = length > 0 ? travelled / length : 1.0;
  out.achieved = distance_m * fraction;
  odom_ = odom_ * Pose2D(out.achieved, 0.0, 0.0);
  out.duration_s = std::abs(out.achieved) / config_.errors.motion.linear_speed_mps;
  clock_s_ += out.duration_s;
  return out;
}

MotionOutput Simulator::rotate(double angle_rad) {
  const std::string problem = checkRotation(angle_rad, config_.max_rotate_rad);
  if (!problem.empty()) throw std::invalid_argument(problem);
  MotionOutput out;
  out.min_clearance_m = kClearanceRange;
  const Pose2D start = true_world_;
  const Pose2D delta = sampleRotation(config_.errors.motion, angle_rad, rng_);
  const Pose2D next = true_world_ * delta;
  if (bodyCollides(Eigen::Vector2d(next.x, next.y))) {
    // The drift while turning would push the robot into an obstacle: it turns in place instead.
    true_world_ = true_world_ * Pose2D(0, 0, delta.yaw);
  } else {
    true_world_ = next;
  }
  out.achieved = angle_rad;
  // A disc turning in place keeps its clearance; the drift while turning moves it from the start
  // to the end (a few millimetres).
  for (const Pose2D& p : {start, true_world_})
    out.min_clearance_m = std::min(out.min_clearance_m, bodyClearance(Eigen::Vector2d(p.x, p.y)));
  odom_ = odom_ * Pose2D(0.0, 0.0, angle_rad);
  out.duration_s = std::abs(angle_rad) / config_.errors.motion.angular_speed_radps;
  clock_s_ += out.duration_s;
  return out;
}

}  // namespace sim
}  // namespace scanstop
