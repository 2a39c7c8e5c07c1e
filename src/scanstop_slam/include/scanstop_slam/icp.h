#pragma once
/// ICP after thesis Algorithm 4 (chapter 4): nearest-neighbour correspondences within c_max,
/// translation from the centroids, rotation from the SVD of the correlation matrix, iterated until
/// the change per iteration is below t_c and r_c. `3dof` (thesis 4.3: 2x2 correlation, rotation
/// about z, z still counts in the correspondence search) or `6dof` (full 3x3).
///
/// The target is a VoxelMap: a persistent voxel hash over all map points that grows with every
/// scan and is never rebuilt.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

namespace scanstop {
namespace slam {

/// What VoxelMap::nearest() knows about the surface at the point it found (for IcpConfig::same_side).
struct Surface {
  bool planar = false;                                 ///< the point's voxel holds one plane (normal is valid)
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();    ///< that plane's unit normal (either sign)
  Eigen::Vector3f view = Eigen::Vector3f::Zero();      ///< unit vector from the point to the sensor that saw it (zero: not known)
};

/// A voxel hash of map points for nearest-neighbour queries within a fixed radius.
class VoxelMap {
 public:
  /// voxel_m >= the query radius (one ring of neighbour voxels is searched);
  /// max_points_per_voxel bounds memory and query time on dense surfaces.
  /// min_spacing_m > 0: a point joins only when no stored point of its voxel is closer than this,
  /// so the map samples surfaces evenly however the scans' line patterns fall (0 = first come).
  explicit VoxelMap(double voxel_m = 0.1, int max_points_per_voxel = 30, double min_spacing_m = 0.0);

  /// Adds points (map frame); non-finite points are ignored. sensor_origin (map frame), when
  /// given, is where the points were seen from: each point keeps its direction (Surface::view).
  void add(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f* sensor_origin = nullptr);
  /// Nearest stored point within radius_m of q (exact; radius_m beyond the voxel size searches more
  /// rings of voxels); false if none. horizontal (when
  /// given) tells whether that point's voxel holds a horizontal surface (floor, ceiling, table top);
  /// surface (when given) the voxel's plane and the direction the point was seen from.
  bool nearest(const Eigen::Vector3f& q, double radius_m, Eigen::Vector3f& out, float& dist2,
               bool* horizontal = nullptr, Surface* surface = nullptr) const;

  size_t size() const { return size_; }
  double voxelSize() const { return voxel_; }
  /// All stored points (for visualization).
  std::vector<Eigen::Vector3f> points() const;

 private:
  using Key = int64_t;
  static Key key(int x, int y, int z);
  /// The voxel coordinates of a key(x, y, z): the inverse of key().
  static void decode(Key k, int& x, int& y, int& z);
  double voxel_;
  int max_per_voxel_;
  float min_spacing2_;
  size_t size_ = 0;
  /// A voxel's points as blocks of kLanes points, each block x[kLanes], y[kLanes], z[kLanes]
  /// (structure of arrays within a block; the last block's unused lanes hold +inf), so nearest()
  /// computes a whole block's squared distances with SIMD instructions of the baseline ISA.
  static constexpr int kLanes = 8;
  struct Cell {
    Key key = 0;                ///< key(x, y, z) of the voxel
    std::vector<float> blocks;  ///< 3 * kLanes floats per block
    std::vector<int8_t> views;  ///< per point: Surface::view, 3 components * 127 (zeros: not known)
    uint32_t count = 0;         ///< points stored (in the order they were added)
    bool horizontal = false;    ///< the points lie on a horizontal plane (PCA normal within 20 deg of z)
    /// The points here and in the 6 face neighbours lie on one plane or on parallel ones (a thin
    /// wall): the smallest PCA spread below 0.3 times the middle one; normal is its direction.
    bool planar = false;
    Eigen::Vector3f normal = Eigen::Vector3f::Zero();
    Eigen::Vector3f point(size_t i) const {
      const float* b = &blocks[(i / kLanes) * 3 * kLanes + i % kLanes];
      return Eigen::Vector3f(b[0], b[kLanes], b[2 * kLanes]);
    }
    Eigen::Vector3f view(size_t i) const {
      return Eigen::Vector3f(views[3 * i], views[3 * i + 1], views[3 * i + 2]) / 127.0f;
    }
    void push(const Eigen::Vector3f& p, const Eigen::Vector3f& view);
  };
  static void classify(Cell& cell);
  /// Cell::normal and Cell::planar from the points of the cell and its 6 face neighbours (add()
  /// computes them for the cells a scan touched, not for their neighbours).
  void estimateNormal(Cell& cell) const;

  /// 4x4x4 voxels: which of them hold points (bit (x & 3) | (y & 3) << 2 | (z & 3) << 4) and their
  /// indices into cells_. A query's neighbour voxels mostly share its brick, so one hash lookup
  /// serves many of them, and an empty one costs a bit test instead of a probe (on the room pair at
  /// c_max 0.1 m over half of the voxels a query looks up are empty).
  struct Brick {
    Key key = 0;
    uint64_t occupied = 0;
    int32_t cells[64];
  };
  static int brickBit(int x, int y, int z) { return (x & 3) | (y & 3) << 2 | (z & 3) << 4; }
  /// Open-addressing hash (linear probing, power-of-two table, at most half full) from brick key
  /// (key(x >> 2, y >> 2, z >> 2)) to an index into bricks_: one flat array probe per lookup
  /// instead of a node-based map's chain.
  int32_t findBrick(Key k) const;
  int32_t findOrAddCell(int x, int y, int z);
  /// The cell of voxel (x, y, z), -1 if it holds no points.
  int32_t findCell(int x, int y, int z) const;
  void growTable();
  std::vector<Cell> cells_;
  std::vector<Brick> bricks_;
  std::vector<Key> slot_keys_;
  std::vector<int32_t> slot_bricks_;  ///< -1: empty slot
  size_t slot_mask_ = 0;
};

/// ICP parameters (thesis optimum as defaults).
struct IcpConfig {
  double c_max_m = 0.10;              ///< correspondence distance [m]
  double t_c_m = 0.0005;              ///< convergence: translation change per iteration [m]
  double r_c_rad = 0.02 * M_PI / 180; ///< convergence: rotation change per iteration [rad]
  int max_iterations = 100;
  bool six_dof = false;               ///< false: 3dof (rotation about z, translation in x, y)
  bool accelerate = true;             ///< Besl-McKay extrapolation of consistent steps (fewer iterations)
  /// 3dof: leave out correspondences on horizontal surfaces (floor, ceiling). They cannot fix x, y or
  /// yaw, but their near-identity pairs outnumber the walls' and hold every step back.
  bool ignore_horizontal = true;
  /// Narrow or skip each point's nearest-neighbour search with bounds from its last search (exact:
  /// the same correspondences as a full c_max search; false only to check that in tests).
  bool reuse_search_bounds = true;
  /// Each map point pairs with one source point at most, the nearest; the others sharing it have no
  /// partner in that iteration. Point-to-point ICP otherwise pulls a scan back onto the map: where
  /// the scan reaches past the map's edge (new ground, a wall running on past the range of the
  /// earlier scans) every source point up to c_max beyond the edge pairs with the edge, all
  /// pulling the same way (room_10x8 route: a scan held at the true pose slides 4-7 cm, with tight
  /// t_c up to 1 m, towards the earlier scans). Steps become small, so it needs a tight t_c / r_c
  /// (IcpSlam's refinement stage).
  bool unique_matches = false;
  /// With the sensor origins known (VoxelMap::add's sensor_origin, icp()'s source_origin): a pair
  /// whose two points were seen from opposite sides of the map point's plane is no pair. The two
  /// faces of a thin wall are otherwise one surface to ICP: room_10x8's corridor lies behind a
  /// 10 cm wall, and the first corridor scans slid 4-6 cm onto the room side of it.
  bool same_side = true;
  // Failure detection.
  int min_correspondences = 200;
  double min_overlap = 0.05;          ///< correspondences / source points
  double max_correction_m = 1.0;      ///< a correction of the initial guess larger than this fails [m]
  double max_correction_rad = 0.5;    ///< ... or a rotation larger than this [rad]
  void validate() const;
};

/// The outcome of one registration.
struct IcpResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();  ///< maps source points into the target frame
  bool converged = false;       ///< converged within max_iterations and passed the checks
  std::string failure;          ///< why not (empty when converged)
  int iterations = 0;
  size_t correspondences = 0;
  double rms_m = 0.0;           ///< RMS distance of the final correspondences [m]
  double overlap = 0.0;         ///< correspondences / source points
};

/// Registers source points (in their own frame) to the map, starting at T_init (source -> map).
/// source_origin: where the source points were seen from (their frame), for IcpConfig::same_side.
IcpResult icp(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source, const Eigen::Isometry3d& T_init,
              const IcpConfig& config, const Eigen::Vector3f* source_origin = nullptr);

/// Keeps one point per voxel (the first); voxel_m <= 0 returns the finite points unchanged.
std::vector<Eigen::Vector3f> voxelDownsample(const std::vector<Eigen::Vector3f>& points, double voxel_m);

}  // namespace slam
}  // namespace scanstop
