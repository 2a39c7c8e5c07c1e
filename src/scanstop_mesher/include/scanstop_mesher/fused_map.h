#pragma once
/// The fused volumetric map (issue #20): a truncated signed distance field (TSDF) over sparse
/// OpenVDB grids into which every registered scan is integrated with its sensor origin. Each
/// reading updates the voxels its beam crosses: inside the truncation band around the hit the
/// signed distance along the beam (positive in front of the surface, on the free side; negative
/// behind it) enters a weighted running average; before the band the voxels get "free" (+truncation)
/// updates, so a spurious reading that later scans see through averages away. The zero crossing of
/// the averaged field is the fused surface: sub-voxel, with the noise of all scans averaged
/// (thesis 8: "the inaccuracies of all scans accumulate in the map"; thesis 9: Marching Cubes).
///
/// Voxel (i,j,k) is centred at (i,j,k) * voxel_m in the map frame (OpenVDB's convention). A voxel
/// is "observed" when its weight (number of readings that updated it, capped at max_weight) is at
/// least min_weight. Surfaces are only taken from cells (the cube between voxels (i,j,k) and
/// (i+1,j+1,k+1)) whose 8 corner voxels are all observed: unseen space stays a hole.
///
/// OpenVDB stays out of this header (it is heavy to compile); the grids live in the implementation.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_common/error.h"
#include "scanstop_mesher/decimate.h"
#include "scanstop_mesher/mesher.h"

namespace scanstop {
namespace mesher {

/// The fused map's grids would pass FusedMapConfig::max_grid_mb (a ConfigError: the voxel is too
/// fine for the mapped space, or the bound too small for it).
class GridBoundError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

/// Settings of the fused map.
struct FusedMapConfig {
  /// Voxel edge [m], [0.001, 1]. 0.02: the scale of the sensor noise (URG-04LX: 1 cm up to 1 m,
  /// 1 % of the range beyond), so the averaged surface is sub-voxel without a huge voxel count.
  double voxel_m = 0.02;
  /// Half width of the band around each hit that gets signed distances [m], [2 * voxel_m, 1].
  /// 0.06 = 3 voxels = 3 sigma of a reading at 2 m (2 cm): a noisy reading near the surface is
  /// not clipped by the band, so the running average of the distances is unbiased.
  double truncation_m = 0.06;
  /// Free space carved before the band along each beam [m], [0, 1000]: voxels the beam crosses at
  /// more than truncation_m before its hit and at most truncation_m + carve_m get a +truncation_m
  /// update. 0 = no carving; the default (1000) carves the whole beam from the sensor origin.
  double carve_m = 1000.0;
  /// Lateral reach of each reading's band [voxels], [0, 3]. 0: only the voxels the beam crosses;
  /// s > 0: in every voxel slice across the beam's main axis, the (2s+1) x (2s+1) voxels around the
  /// beam (each with its own distance along the beam), so beams up to 2s+1 voxels apart (far
  /// readings, sparse planes) still give a gap-free band. The free-space carving stays one voxel wide.
  /// Default 0: the lateral neighbours get the beam's distance along it, which is off on tilted and
  /// curved surfaces and at the rim of what was seen (sphere test: max vertex error 3.6 -> 5.9 mm).
  int splat = 0;
  /// Weight a voxel needs to count as observed (for surface points and the mesh), [1, max_weight].
  /// 2: a surface needs two readings; one reading alone (a random reading) never makes a surface.
  double min_weight = 2.0;
  /// Cap of the weight (the running average then becomes a moving one that can still change), [1, 1e6].
  double max_weight = 10000.0;
  /// Bound on the memory of the grids [MB], [1, 1e6]: integrate() throws GridBoundError once the leaf
  /// nodes it allocated (8^3 voxels each, in both grids; the internal nodes add up to a quarter more
  /// at a voxel far too fine, 25 MB at a 20 MB bound measured) would pass it: a voxel too fine for the mapped
  /// space (--voxel 0.001 on a room wanted 9 GB and more) ends at once instead of filling memory.
  /// 500 MB: about 0.8 GB for the whole process. Two 50-plane room_10x8 scans at 0.02 m: 50 MB with
  /// carve_m 0.2, 180 MB carving whole beams.
  double max_grid_mb = 500.0;
  /// Only voxels whose x index lies in [clip_x_min_voxel, clip_x_max_voxel] are updated (voxel i is
  /// centred at x = i * voxel_m): one slab of a map too large for max_grid_mb as a whole
  /// (meshFusedMapDirectory). Each voxel inside gets exactly the updates it gets without the clip,
  /// in the same order. Default: every voxel.
  /// After carve_m: integrateMapDirectory carves every beam's free space before carve_m as well (a
  /// second pass, FusedMap::carveFar), in the voxels that exist by then (near some surface) only:
  /// what whole-beam carving does to the surfaces (it removes a surface that other scans see through
  /// from afar: the 10 cm "pillar" round a retroreflective table leg, mixed pixels behind edges) at a
  /// fraction of its cost, as the beam skips the space where no voxel exists leaf by leaf.
  bool carve_far = false;
  /// Threads integrateMapDirectory uses, [1, 16]: the scans are split into that many runs of
  /// consecutive scans, each integrated into grids of its own (each within max_grid_mb / threads),
  /// then merged voxel by voxel (weighted means of the fields, weights summed); the far pass counts
  /// each thread's free updates apart and adds them at the end. The same field as one thread in
  /// exact arithmetic (floats round differently; no weight near max_weight); deterministic. 2: the
  /// machine's two cores (room_10x8's 34 scans: 20.6 s -> 11 s).
  int threads = 2;
  int clip_x_min_voxel = std::numeric_limits<int>::min();
  int clip_x_max_voxel = std::numeric_limits<int>::max();
  /// Throws ConfigError naming the field, its value and the allowed range.
  void validate() const;
};

/// Counts and times of an integration (cumulative over the map's life).
struct FusedMapStats {
  size_t scans = 0;                ///< integrate() calls
  size_t points = 0;               ///< finite readings integrated
  size_t skipped_points = 0;       ///< readings skipped: not finite (the scanner's invalid readings), or at the origin
  size_t voxel_updates = 0;        ///< voxel updates (band and free space)
  size_t leaves_created = 0;       ///< leaf nodes (8^3 voxels) allocated in each grid (bounded by max_grid_mb)
  double integrate_seconds = 0.0;  ///< wall time (integrateMapDirectory: of all its threads together)
};

class FusedMap {
 public:
  /// Validates the config (ConfigError naming the field).
  explicit FusedMap(const FusedMapConfig& config = FusedMapConfig());
  ~FusedMap();
  FusedMap(FusedMap&&) noexcept;
  FusedMap& operator=(FusedMap&&) noexcept;
  FusedMap(const FusedMap&) = delete;
  FusedMap& operator=(const FusedMap&) = delete;

  const FusedMapConfig& config() const { return config_; }

  /// Integrates one scan: points [m] and the sensor origin [m], both in the map frame. Points that
  /// are not finite or lie at the origin are skipped (counted in stats().skipped_points). Throws
  /// ConfigError when the origin is not finite, or when the grids would pass max_grid_mb (the scan is
  /// then partly integrated: discard the map). Returns the number of points integrated.
  size_t integrate(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin);

  /// FusedMapConfig::carve_far's second pass for one scan (integrated before, with every other scan):
  /// each beam's voxels farther than truncation_m + carve_m before its hit that exist already get a
  /// free (+truncation_m) update, as integrate() gives the voxels within carve_m; no voxel is created.
  /// Returns the voxels updated. Throws ConfigError for an origin that is not finite.
  size_t carveFar(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin);

  /// Takes back integrate(points, origin) of a scan integrated before with exactly these points and
  /// origin (the scan moved: SLAM corrected its pose): every voxel update is undone (the running
  /// average's step backwards; a voxel left without readings is unseen again). Exact in exact
  /// arithmetic while no weight reached max_weight. No voxel is created. Returns the readings.
  size_t deintegrate(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin);

  /// Loads scan s of a run of scans in the map frame with its sensor origin; false: it cannot be read
  /// (left out).
  using ScanLoader = std::function<bool(size_t s, std::vector<Eigen::Vector3f>& points, Eigen::Vector3f& origin)>;
  /// The far carving pass (carveFar) of scans [0, scans) after all of them were integrated, on
  /// `threads` threads (runs of consecutive scans): each thread counts its free updates per voxel apart
  /// (the field stays as it is while they walk), the counts are added at the end: carveFar of every
  /// scan in exact arithmetic. Rethrows a loader's exception.
  void carveFarAll(size_t scans, const ScanLoader& load, int threads);
  /// A deep copy (grids, stats).
  FusedMap copy() const;

  /// Points on the zero crossing, one per surface cell (all 8 corners observed, a sign change):
  /// the mean of the cell's edge crossings (linear interpolation along the edges), moved onto the
  /// zero level of the cell's trilinear field by one Newton step. Normals: the field's gradient
  /// there, normalized, pointing to the observed free (positive) side. `origins`/`view` stay empty.
  ScanPoints surfacePoints() const;
  /// Those of the cells whose x index lies in [cell_x_min, cell_x_max) (cell i spans voxel centres i
  /// and i + 1 along x): one slab's own.
  ScanPoints surfacePoints(int cell_x_min, int cell_x_max) const;

  /// A triangle mesh of the zero level set: openvdb::tools::volumeToMesh (isovalue 0, adaptivity 0),
  /// quads split into two triangles, only polygons whose vertices lie in surface cells (all 8
  /// corners observed; the rest would border unseen space). Faces are counter-clockwise seen from
  /// the free side; vertex normals are the field's gradient (towards the free side). Where two
  /// sheets meet in one vertex (at the rim of the seen space) only its largest fan is kept
  /// (dropPinchedFans), so the mesh is manifold.
  TriangleMesh extractMesh() const;
  /// One slab's part of that mesh: the polygons whose cells' smallest x index lies in
  /// [cell_x_min, cell_x_max) (every polygon of the map belongs to exactly one slab of a partition),
  /// pinched fans not yet dropped (weldSlabMeshes does, over the whole).
  TriangleMesh extractSlabMesh(int cell_x_min, int cell_x_max) const;

  /// Signed distance [m] and weight of the voxel containing the point p [m] (map frame); weight 0
  /// (and distance truncation_m) for a voxel never updated.
  float distanceAt(const Eigen::Vector3f& p) const;
  float weightAt(const Eigen::Vector3f& p) const;

  /// Adds another map's readings (scans integrated there and not here, the same voxel, truncation,
  /// clip and max_weight): per voxel the weighted mean of both fields, the weights summed (capped).
  /// Throws GridBoundError when the grids would pass max_grid_mb (the map is then partly merged:
  /// discard it), ConfigError for another voxel or truncation.
  void merge(const FusedMap& other);

  /// Voxels ever updated (active in the grids).
  size_t activeVoxels() const;
  /// Voxels with weight >= min_weight.
  size_t observedVoxels() const;
  /// Memory of both grids [bytes] (OpenVDB's memUsage).
  size_t memoryBytes() const;
  const FusedMapStats& stats() const { return stats_; }

  /// Writes both grids ("tsdf", "weight") as an OpenVDB file (.vdb). Throws IoError naming the file.
  void save(const std::string& path) const;

 private:
  size_t integrateSigned(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& origin, bool remove);
  friend size_t integrateMapDirectory(FusedMap&, const std::string&, std::vector<std::string>*,
                                      const std::vector<uint8_t>*);
  struct Grids;
  /// Share of max_grid_mb this map may use (one thread's of integrateMapDirectory).
  double bound_share_ = 1.0;
  FusedMapConfig config_;
  std::unique_ptr<Grids> grids_;
  FusedMapStats stats_;
};

/// Integrates every scan of a map directory (scanstop_common/map_dir.h), one scan at a time, at its
/// map pose with its sensor origin (map_pose * sensor_origin). Strict like loadMapDirectory: throws
/// IoError naming the file for a missing poses.csv, any problem of the directory, an unreadable scan
/// or a map without scans; with `skipped` given, problems and unreadable scans are appended there
/// instead (naming the file) and the good scans are integrated (IoError still when none is left).
/// With `only` (one flag per scan of the directory, in its order), the scans whose flag is 0 are not
/// read (0 returned when none is chosen); each thread still takes its run of all the scans, so a voxel
/// gets the same updates in the same order as long as the scans that reach it are chosen (the slabs of
/// meshFusedMapInSlabs). std::invalid_argument when `only` has another size.
/// Returns the number of scans integrated.
size_t integrateMapDirectory(FusedMap& map, const std::string& dir, std::vector<std::string>* skipped = nullptr,
                             const std::vector<uint8_t>* only = nullptr);

/// Runs work(t) for t in [0, threads) on as many threads (the caller's is the first); rethrows the
/// first thread's exception (in thread order) after all are done.
void runInThreads(int threads, const std::function<void(int)>& work);

/// A mesh of a map directory made through its fused map (bpa_mesher_node's `mesh_method`).
struct FusedMesh {
  TriangleMesh mesh;
  size_t scans = 0;           ///< scans integrated
  size_t surface_points = 0;  ///< fused surface points meshed ("fused_bpa")
  std::vector<Eigen::Vector3f>
      surface;               ///< the fused map's surface points (for display; Marching Cubes: its vertices) [m]
  std::string save_problem;  ///< why save_path could not be written ("" when it was, or none given)
  size_t voxels = 0;         ///< active voxels of the fused map (summed over slabs)
  size_t memory_bytes = 0;   ///< of its grids (the largest slab's)
  size_t slabs = 1;          ///< slabs along x it was built in (1: the whole map at once)
  size_t scans_read = 0;     ///< scans integrated over all slabs (each slab reads the scans that reach it)
  DecimateStats decimated;   ///< slabs decimated one by one (decimate_slabs): summed over them; else empty
  double integrate_s = 0.0, mesh_s = 0.0;
};
/// The methods meshFusedMapDirectory takes: "marching_cubes" (FusedMap::extractMesh) and
/// "fused_bpa" (Ball Pivoting of FusedMap::surfacePoints with their normals).
bool isFusedMeshMethod(const std::string& method);
/// Integrates every scan of the map directory (integrateMapDirectory, same errors) and meshes the
/// fused map by `method` (`bpa`: the Ball Pivoting settings of "fused_bpa"); with `save_path`, the
/// fused map is written there too (FusedMap::save, .vdb; a failure is said in save_problem, the mesh
/// stands). A map whose grids would pass config.max_grid_mb is built and meshed in slabs along x
/// instead (halved until each fits, down to min_slab_m; the slabs' meshes meet exactly and are
/// welded, then pinched fans dropped over the whole): the same mesh within float rounding, memory
/// bounded by one slab; no .vdb then (slabs > 1 says so); decimate_slabs as meshFusedMapInSlabs
/// (the whole map's mesh is left to the caller: decimated.faces_before 0). Throws GridBoundError when a
/// min_slab_m slab does not fit, std::invalid_argument for another method and std::runtime_error
/// when the fused map holds no observed surface.
FusedMesh meshFusedMapDirectory(const std::string& dir, const FusedMapConfig& config, const std::string& method,
                                const MesherConfig& bpa, std::vector<std::string>* skipped = nullptr,
                                const std::string& save_path = "", double min_slab_m = 1.0,
                                const DecimateConfig* decimate_slabs = nullptr);
/// meshFusedMapDirectory's slabs without its attempt at the whole map first (for a caller that saw
/// the whole pass max_grid_mb): two halves along x of the map's readings, each built alone
/// (FusedMapConfig::clip_x_*_voxel) from the scans whose beams reach it (their x range, origin
/// included, widened by the band and the splat) and halved again while it passes the bound; same errors.
/// With decimate_slabs (Marching Cubes), each slab's mesh is decimated before the next is built (its
/// cut at the slab's borders is boundary, which decimation keeps, so the slabs still meet exactly): the
/// memory stays that of a slab, not of the whole undecimated mesh; the caller does not decimate again.
FusedMesh meshFusedMapInSlabs(const std::string& dir, const FusedMapConfig& config, const std::string& method,
                              const MesherConfig& bpa, std::vector<std::string>* skipped = nullptr,
                              double min_slab_m = 1.0, const DecimateConfig* decimate_slabs = nullptr);

}  // namespace mesher
}  // namespace scanstop
