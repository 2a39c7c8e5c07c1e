#pragma once
/// ICP after thesis Algorithm 4 (chapter 4): nearest-neighbour correspondences within c_max,
/// translation from the centroids, rotation from the SVD of the correlation matrix, iterated until
/// the change per iteration is below t_c and r_c. `3dof` (thesis 4.3: 2x2 correlation, rotation
/// about z, z still counts in the correspondence search) or `6dof` (full 3x3).
///
/// The target is a VoxelMap: a persistent voxel hash over all map points that grows with every
/// scan and is never rebuilt.
///
/// Beside it (IcpConfig::method) point-to-plane ICP: one Gauss-Newton step per iteration on
/// sum ((R p + t - m) . n)^2 over the pairs whose map point's voxel is planar (n: VoxelMap's
/// per-voxel normal). Either method reports the Gauss-Newton Hessian of those point-to-plane
/// residuals at its result (IcpResult::information) and, where it is nearly singular (a
/// corridor), keeps the initial guess along its weak directions (IcpConfig::degeneracy_remap).

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_set>
#include <vector>

namespace scanstop {
namespace slam {

/// What VoxelMap::nearest() knows about the surface at the point it found (for IcpConfig::same_side).
struct Surface {
  bool planar = false;                               ///< the point's voxel holds one plane (normal is valid)
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< that plane's unit normal (either sign)
  Eigen::Vector3f view =
      Eigen::Vector3f::Zero();  ///< unit vector from the point to the sensor that saw it (zero: not known)
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

/// What icp() minimizes per iteration (IcpConfig::method).
enum class IcpMethod {
  /// Thesis Algorithm 4: sum |R p + t - m|^2 in closed form (centroids + SVD), every pair.
  point_to_point,
  /// One Gauss-Newton step on sum ((R p + t - m) . n)^2 over the pairs with a planar map normal n
  /// (Surface::planar); pairs without one are left out (no point-to-point fallback: on a plane
  /// their along-plane terms are what makes point-to-point slide).
  point_to_plane,
};
/// "point_to_point" / "point_to_plane".
std::string toString(IcpMethod method);
/// The inverse of toString(); ConfigError naming `name` for anything else.
IcpMethod parseIcpMethod(const std::string& text, const std::string& name = "method");

/// ICP parameters (thesis optimum as defaults).
///
/// Pose parameters of the information matrix and of degeneracy_remap: a perturbation of the pose
/// in its own frame, T * [R(w), t]: 3dof (t_x, t_y, w_z), 6dof (t_x, t_y, t_z, w_x, w_y, w_z); t
/// in m along the source frame's axes, w in rad about its origin (so one radian weighs like one
/// metre: eigenvalues and directions mix the two units as a scene of metres does).
struct IcpConfig {
  double c_max_m = 0.10;               ///< correspondence distance [m]
  double t_c_m = 0.0005;               ///< convergence: translation change per iteration [m]
  double r_c_rad = 0.02 * M_PI / 180;  ///< convergence: rotation change per iteration [rad]
  int max_iterations = 100;
  bool six_dof = false;    ///< false: 3dof (rotation about z, translation in x, y)
  bool accelerate = true;  ///< Besl-McKay extrapolation of consistent steps (fewer iterations)
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
  /// point_to_point (default: the thesis' ICP, unchanged) or point_to_plane. Point-to-plane does not
  /// use `accelerate` (Gauss-Newton steps do not creep); its convergence test is the step's
  /// translation (t_c) and rotation angle (r_c) in the parameters above. Needs planar voxels in the
  /// map: min_correspondences counts its planar pairs.
  IcpMethod method = IcpMethod::point_to_point;
  /// Degeneracy threshold [1] (dimensionless, range [0, 1], default 0.01): a direction of the
  /// information matrix (eigenvector, in the normalized parameters of IcpResult::eigenvalues) is
  /// weak when its eigenvalue is below degeneracy_ratio times the largest one;
  /// IcpResult::degenerate when the smallest is. 0: nothing is ever weak.
  /// (Measured: the real room pair at c_max 0.5 m 0.12 (condition 8.2), synthetic rooms 0.14-0.35,
  /// room_10x8 route (slam_bench, 6dof point_to_plane) down to 0.018; a corridor with 1 mm noise 1e-5 - 1e-3.)
  double degeneracy_ratio = 0.01;
  /// Keep the initial guess along weak directions (Zhang, Kaess, Singh 2016, solution remapping;
  /// default true). point_to_plane: each Gauss-Newton step is projected onto the well-constrained
  /// eigen-subspace of that step's Hessian. point_to_point: after convergence the whole correction
  /// T_init^-1 T (in the pose parameters above) loses its component along the weak directions of
  /// the final information matrix, and the final figures are evaluated there. No weak direction:
  /// results unchanged, bit for bit.
  bool degeneracy_remap = true;
  /// The registration's own information along weak directions when they are weighed against an
  /// odometry prior (icp()'s prior_information; then degeneracy_remap does not apply): the
  /// point-to-plane pairs' mean
  /// J^T J (IcpResult::information / information_pairs) times information_points independent
  /// pairs over information_sigma_m^2. Neighbouring pairs' errors are not independent (one wall,
  /// one scan line, the map's own offsets), so the count is far below the pairs'. 50 / 1 cm: a
  /// direction whose eigenvalue is 1 % of the largest (the degeneracy_ratio) is held to about
  /// 2 cm, like the odometry of a 1-2 m leg, so the two weigh about alike there.
  /// With a prior's information: weigh it in every direction (each Gauss-Newton step minimizes the
  /// weighted pairs plus the prior; point-to-point's result gets one such step), not only along
  /// the weak ones.
  bool prior_all_directions = false;
  double information_points = 50.0;   ///< [1], (0, 1e6]
  double information_sigma_m = 0.01;  ///< [m], (0, 1]
  // Failure detection.
  int min_correspondences = 200;
  double min_overlap = 0.05;        ///< correspondences / source points
  double max_correction_m = 1.0;    ///< a correction of the initial guess larger than this fails [m]
  double max_correction_rad = 0.5;  ///< ... or a rotation larger than this [rad]
  void validate() const;
};

/// The outcome of one registration.
struct IcpResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();  ///< maps source points into the target frame
  bool converged = false;  ///< converged within max_iterations and passed the checks
  std::string failure;     ///< why not (empty when converged)
  int iterations = 0;
  size_t correspondences = 0;
  double rms_m = 0.0;    ///< RMS distance of the final correspondences [m]
  double overlap = 0.0;  ///< correspondences / source points
  /// Gauss-Newton Hessian J^T J of the point-to-plane residuals (R p + t - m) . n of the final pairs
  /// with a planar map normal, at the result (either method), over the pose parameters of
  /// IcpConfig (3x3 for 3dof, 6x6 for 6dof) [1/m^2 per residual m^2; unweighted sum over pairs].
  /// 3dof with ignore_horizontal: without the horizontal pairs, as the solve. Empty if no pair.
  Eigen::MatrixXd information;
  size_t information_pairs = 0;  ///< pairs in it (planar map normal)
  /// Eigenvalues (ascending) of the information matrix in normalized pose parameters: translation
  /// [m], and rotation about the centroid c of those pairs' source points times their RMS distance
  /// L from c [m] (3dof: horizontal distance); i.e. A^T information A with t = t' + c x w, w = u / L.
  /// Unit-free that way: a 15 cm object and a 30 m corridor, a source origin at the points or far
  /// from them (where a rotation is mostly a translation), compare alike. [m^2 per m^2 residual]
  Eigen::VectorXd eigenvalues;
  /// Largest / smallest of those eigenvalues [1] (inf when the smallest is <= 0; NaN without information).
  double condition = std::numeric_limits<double>::quiet_NaN();
  /// The eigenvector of the smallest eigenvalue mapped back to the pose parameters of IcpConfig
  /// (3dof: x, y, yaw; 6dof: x, y, z, roll-, pitch-, yaw-axis rotation), unit length, sign: its
  /// largest component positive; empty without information. A corridor along x: ~(1, 0, 0).
  Eigen::VectorXd weak_direction;
  /// smallest / largest eigenvalue < IcpConfig::degeneracy_ratio (false without information).
  bool degenerate = false;
  int weak_directions = 0;  ///< eigenvalues below degeneracy_ratio times the largest
  /// degeneracy_remap changed the result (point_to_point: the correction was projected;
  /// point_to_plane: some step had a weak direction).
  bool remapped = false;
  /// With a weighed prior (icp()'s prior_information) on a degenerate registration: how far the
  /// result lies from where solution remapping would have kept it (what the weak directions' own
  /// pairs added against the prior), at the robot [m] and in angle [rad]. 0 otherwise.
  double weak_gain_m = 0.0;
  double weak_gain_rad = 0.0;
};

/// Registers source points (in their own frame) to the map, starting at T_init (source -> map).
/// source_origin: where the source points were seen from (their frame), for IcpConfig::same_side.
/// prior: with degeneracy_remap, the pose kept along the result's weak directions (default: T_init).
/// A stage that starts from an earlier stage's result passes the first stage's guess (the odometry
/// prior), so that no stage slides along a direction the final pairs cannot fix: both methods then
/// project the whole correction prior^-1 T back onto the well-constrained directions at the end.
/// prior_information (3x3 for 3dof, 6x6 for 6dof; the inverse covariance of the prior in the pose
/// parameters of IcpConfig at the prior [1/m^2, 1/rad^2]), when given, replaces that hard remap
/// by weighing along the weak directions (whatever degeneracy_remap says): there the step
/// minimizes the pairs' residuals (weighted as IcpConfig::information_points /
/// information_sigma_m say) plus the prior's Mahalanobis distance, so a corridor's axis takes what
/// its door jambs' few pairs and the odometry of the leg know of it in proportion. The
/// well-constrained directions are the pairs' alone, as without a prior.
IcpResult icp(const VoxelMap& target, const std::vector<Eigen::Vector3f>& source, const Eigen::Isometry3d& T_init,
              const IcpConfig& config, const Eigen::Vector3f* source_origin = nullptr,
              const Eigen::Isometry3d* prior = nullptr, const Eigen::MatrixXd* prior_information = nullptr);

/// Keeps one point per voxel (the first); voxel_m <= 0 returns the finite points unchanged.
std::vector<Eigen::Vector3f> voxelDownsample(const std::vector<Eigen::Vector3f>& points, double voxel_m);

/// voxelDownsample() over a cloud that grows: add() keeps each finite point whose voxel holds no
/// kept point yet, so after any sequence of add()s points() is voxelDownsample() of everything
/// added, in that order, at a cost proportional to the points added, not to all kept so far
/// (icp_slam_node's slam/map_cloud: on a 791-scan office floor, 35 M map points, downsampling the
/// whole map after every scan took 2.4 s).
class VoxelDownsampler {
 public:
  /// voxel_m <= 0 keeps every finite point.
  explicit VoxelDownsampler(double voxel_m) : voxel_m_(voxel_m) {}
  void add(const std::vector<Eigen::Vector3f>& points);
  const std::vector<Eigen::Vector3f>& points() const { return points_; }

 private:
  double voxel_m_;
  std::unordered_set<int64_t> seen_;
  std::vector<Eigen::Vector3f> points_;
};

/// One point per voxel: the mean of the voxel's finite points (in the order the voxels were first
/// hit); voxel_m <= 0 returns the finite points unchanged. Unlike voxelDownsample's first point,
/// which sits where the scanner's sweep entered the voxel (a bias along the sweep, i.e. in yaw),
/// the mean is unbiased and averages the range noise.
std::vector<Eigen::Vector3f> voxelCentroids(const std::vector<Eigen::Vector3f>& points, double voxel_m);

}  // namespace slam
}  // namespace scanstop
