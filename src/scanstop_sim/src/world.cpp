#include "scanstop_sim/world.h"

#include <sys/stat.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "scanstop_common/error.h"
#include "scanstop_common/stl_io.h"

namespace scanstop {
namespace sim {
namespace {

using Poly3 = std::vector<Eigen::Vector3d>;

/// Keeps the part of a convex polygon with sign * (z - z0) >= 0 (Sutherland-Hodgman, one plane).
Poly3 clipZ(const Poly3& in, double z0, double sign) {
  Poly3 out;
  for (size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector3d& a = in[i];
    const Eigen::Vector3d& b = in[(i + 1) % in.size()];
    const double da = sign * (a.z() - z0), db = sign * (b.z() - z0);
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

void embreeError(void*, RTCError code, const char* str) {
  throw std::runtime_error(std::string("Embree error ") + std::to_string(static_cast<int>(code)) + ": " +
                           (str ? str : ""));
}

}  // namespace

struct World::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

World::World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

RTCScene World::scene() const { return embree_->scene; }

World World::load(const std::string& path, const WorldOptions& options) {
  WorldOptions o = options;
  if (o.materials_file.empty()) {
    // The materials file next to the STL, when there is one.
    const std::string sibling = materialsPathFor(path);
    struct stat st;
    if (::stat(sibling.c_str(), &st) == 0) o.materials_file = sibling;
  }
  return fromMesh(readStl(path), path, o);
}

void World::setMaterials(const MaterialMap& materials) {
  materials_ = materials;
  face_region_.clear();
  if (materials_.regions.empty()) return;
  face_region_.assign(mesh_.faces.size(), -1);
  for (size_t f = 0; f < mesh_.faces.size(); ++f) {
    const Eigen::Vector3d c =
        ((mesh_.vertices[mesh_.faces[f][0]] + mesh_.vertices[mesh_.faces[f][1]] + mesh_.vertices[mesh_.faces[f][2]]) /
         3.0f)
            .cast<double>();
    for (size_t r = 0; r < materials_.regions.size(); ++r)
      if (materials_.regions[r].contains(c)) {
        face_region_[f] = static_cast<int>(r);
        break;
      }
  }
}

std::vector<size_t> World::regionCounts() const {
  std::vector<size_t> counts(materials_.regions.size(), 0);
  for (const int r : face_region_)
    if (r >= 0) ++counts[static_cast<size_t>(r)];
  return counts;
}

World World::fromMesh(const TriangleMesh& mesh, const std::string& name, const WorldOptions& options) {
  if (mesh.faces.empty()) throw IoError(name, "the world has no triangles");
  World w;
  w.name_ = name;
  w.mesh_ = mesh;
  w.min_ = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  w.max_ = -w.min_;
  for (const auto& v : mesh.vertices) {
    if (!v.allFinite()) throw IoError(name, "the world has a non-finite vertex");
    w.min_ = w.min_.cwiseMin(v);
    w.max_ = w.max_.cwiseMax(v);
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    bool flat = true;
    for (int k = 0; k < 3; ++k)
      flat = flat && std::abs(mesh.vertices[mesh.faces[f][k]].z()) <= options.floor_tolerance_m;
    if (flat && mesh.faceNormal(f).norm() > 0.5f) ++w.floor_triangles_;
  }
  if (options.require_floor && w.floor_triangles_ == 0)
    throw IoError(name, "the world has no floor: no triangle lies in the z = 0 plane (within " +
                            std::to_string(options.floor_tolerance_m) +
                            " m); worlds are in metres with the floor at z = 0 (set allow_no_floor to load it anyway)");

  w.embree_ = std::make_unique<Embree>();
  w.embree_->device = rtcNewDevice("threads=0");
  if (!w.embree_->device) throw IoError(name, "Embree could not create a device");
  rtcSetDeviceErrorFunction(w.embree_->device, embreeError, nullptr);
  w.embree_->scene = rtcNewScene(w.embree_->device);
  rtcSetSceneBuildQuality(w.embree_->scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = rtcNewGeometry(w.embree_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.vertices.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), mesh.faces.size()));
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) vb[3 * i + k] = mesh.vertices[i][k];
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (int k = 0; k < 3; ++k) ib[3 * f + k] = static_cast<unsigned>(mesh.faces[f][k]);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(w.embree_->scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(w.embree_->scene);
  w.buildObstacleMap(options);
  w.face_normals_.resize(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3f& a = mesh.vertices[mesh.faces[f][0]];
    const Eigen::Vector3f n = (mesh.vertices[mesh.faces[f][1]] - a).cross(mesh.vertices[mesh.faces[f][2]] - a);
    w.face_normals_[f] = n.norm() > 0.0f ? Eigen::Vector3f(n.normalized()) : Eigen::Vector3f::Zero();
  }
  if (!options.materials_file.empty()) w.setMaterials(loadMaterials(options.materials_file));
  return w;
}

void World::buildObstacleMap(const WorldOptions& options) {
  for (const auto& f : mesh_.faces) {
    Poly3 poly = {mesh_.vertices[f[0]].cast<double>(), mesh_.vertices[f[1]].cast<double>(),
                  mesh_.vertices[f[2]].cast<double>()};
    poly = clipZ(poly, options.obstacle_min_z_m, 1.0);
    if (poly.size() < 2) continue;
    poly = clipZ(poly, options.obstacle_max_z_m, -1.0);
    if (poly.empty()) continue;
    Polygon2D flat;
    for (const auto& v : poly) flat.push_back(v.head<2>());
    polygons_.push_back(flat);
  }
  grid_origin_ = min_.head<2>().cast<double>() - Eigen::Vector2d::Constant(1.0);
  grid_w_ = std::max(1, static_cast<int>(std::ceil((max_.x() - min_.x() + 2.0) / cell_m_)));
  grid_h_ = std::max(1, static_cast<int>(std::ceil((max_.y() - min_.y() + 2.0) / cell_m_)));
  grid_.assign(static_cast<size_t>(grid_w_) * grid_h_, {});
  for (size_t s = 0; s < polygons_.size(); ++s) {
    Eigen::Vector2d lo = polygons_[s][0], hi = polygons_[s][0];
    for (const auto& v : polygons_[s]) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    lo -= grid_origin_;
    hi -= grid_origin_;
    const int x0 = std::clamp(static_cast<int>(lo.x() / cell_m_), 0, grid_w_ - 1);
    const int x1 = std::clamp(static_cast<int>(hi.x() / cell_m_), 0, grid_w_ - 1);
    const int y0 = std::clamp(static_cast<int>(lo.y() / cell_m_), 0, grid_h_ - 1);
    const int y1 = std::clamp(static_cast<int>(hi.y() / cell_m_), 0, grid_h_ - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid_[static_cast<size_t>(y) * grid_w_ + x].push_back(static_cast<int>(s));
  }
}

std::vector<int> World::cellsNear(const Eigen::Vector2d& p, double radius) const {
  std::vector<int> cells;
  const Eigen::Vector2d lo = p - Eigen::Vector2d::Constant(radius) - grid_origin_;
  const Eigen::Vector2d hi = p + Eigen::Vector2d::Constant(radius) - grid_origin_;
  const int x0 = std::clamp(static_cast<int>(std::floor(lo.x() / cell_m_)), 0, grid_w_ - 1);
  const int x1 = std::clamp(static_cast<int>(std::floor(hi.x() / cell_m_)), 0, grid_w_ - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(lo.y() / cell_m_)), 0, grid_h_ - 1);
  const int y1 = std::clamp(static_cast<int>(std::floor(hi.y() / cell_m_)), 0, grid_h_ - 1);
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) cells.push_back(y * grid_w_ + x);
  return cells;
}

double World::distanceTo(const Polygon2D& poly, const Eigen::Vector2d& p) const {
  double best = std::numeric_limits<double>::infinity();
  bool inside = poly.size() >= 3;
  double sign = 0.0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[(i + 1) % poly.size()];
    best = std::min(best, pointSegmentDistance(p, a, b));
    const double cross = (b - a).x() * (p - a).y() - (b - a).y() * (p - a).x();
    if (std::abs(cross) < 1e-12) continue;
    if (sign == 0.0) sign = cross > 0 ? 1.0 : -1.0;
    if (cross * sign < 0) inside = false;
  }
  return (inside && sign != 0.0) ? 0.0 : best;
}

bool World::discCollides(const Eigen::Vector2d& p, double radius) const {
  for (const int c : cellsNear(p, radius))
    for (const int s : grid_[c])
      if (distanceTo(polygons_[s], p) < radius) return true;
  return false;
}

double World::clearanceWithin(const Eigen::Vector2d& p, double max_m) const {
  double best = max_m;
  for (const int c : cellsNear(p, max_m))
    for (const int s : grid_[c]) best = std::min(best, distanceTo(polygons_[s], p));
  return best;
}

double World::clearance(const Eigen::Vector2d& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Polygon2D& poly : polygons_) best = std::min(best, distanceTo(poly, p));
  return best;
}

double World::castRay(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float max_range) const {
  const RayHit h = intersect(origin, direction, 0.0f, max_range);
  return h.hit() ? h.t : std::numeric_limits<double>::infinity();
}

RayHit World::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float tnear,
                        float tfar) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = origin.x();
  rh.ray.org_y = origin.y();
  rh.ray.org_z = origin.z();
  rh.ray.dir_x = direction.x();
  rh.ray.dir_y = direction.y();
  rh.ray.dir_z = direction.z();
  rh.ray.tnear = tnear;
  rh.ray.tfar = tfar;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.ray.time = 0.0f;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(embree_->scene, &context, &rh);
  RayHit h;
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    h.t = rh.ray.tfar;
    h.prim = rh.hit.primID;
  }
  return h;
}

void World::castRays(const std::vector<Eigen::Vector3f>& origins, const std::vector<Eigen::Vector3f>& directions,
                     float max_range, std::vector<float>& ranges) const {
  ranges.resize(directions.size());
  const long n = static_cast<long>(directions.size());
#pragma omp parallel for schedule(static, 1024)
  for (long i = 0; i < n; ++i) {
    ranges[i] = static_cast<float>(castRay(origins[i], directions[i], max_range));
  }
}

}  // namespace sim
}  // namespace scanstop
