#pragma once
/// Ball Pivoting surface reconstruction (Bernardini et al. 1999; thesis chapter 7, Algorithm 6).
///
/// Input: points with unit normals (pointing to the side the surface was seen from). A ball of
/// radius r that touches three points and contains no other point makes a triangle, oriented so
/// that its normal points to the ball centre and agrees (positive dot product) with the normals of
/// its three corners. The front (the boundary of the surface) is a set of loops of directed edges;
/// each active edge is pivoted: among the valid triangles on the edge (ball empty, normals
/// consistent) the one with the smallest pivot angle is chosen, then joined; edges that meet an
/// existing edge of opposite direction are glued (the four cases of thesis 7.3: remove a two-edge
/// loop, remove two adjacent edges, split a loop, merge two loops).
///
/// Guarantees: no edge ever gets a third triangle or two triangles running it in the same
/// direction (consistent orientation); a pivot never uses a vertex inside the surface. A pivot
/// may reach a front vertex outside the fan of the pivot edge (that is how two fronts meet and
/// merge, glue case 4, or a front closes around a gap, case 3); the vertex is pinched until the
/// gap between its fans closes. mesh() returns a manifold: at a vertex still pinched after the
/// last pass, the triangles of all but its largest fan are dropped (counted in the stats).
/// Several radii in increasing order run one after the other on the same surface, the boundary
/// re-activated between passes.
///
/// Large inputs (run()): the points are cut into slabs along their longest axis (equal point
/// counts), each slab is meshed by all passes on its own OpenMP thread (its points are the only
/// vertices it may use; every point still counts for the empty-ball test, so each slab's triangles
/// are valid Ball Pivoting triangles), then the slabs are merged into one front and the seams are
/// stitched by the same passes restricted to the edges and seeds within 2 r of a cut. The result
/// depends on the number of slabs, not on the number of threads (deterministic).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scanstop_common/cloud.h"
#include "scanstop_mesher/spatial_grid.h"

namespace scanstop {
namespace mesher {

/// Counters of one reconstruction (all passes).
struct BpaStats {
  size_t points = 0;       ///< input points (with a finite position and normal)
  size_t used_points = 0;  ///< points that are a vertex of some triangle
  size_t triangles = 0;
  size_t seeds = 0;                             ///< seed triangles
  size_t pivots = 0;                            ///< pivot attempts
  size_t joins = 0;                             ///< triangles added by pivoting
  std::array<size_t, 4> glue = {{0, 0, 0, 0}};  ///< glue cases 1..4 (thesis 7.3)
  size_t refused_interior = 0;                  ///< pivot reached a vertex inside the surface
  size_t refused_edge = 0;                      ///< the triangle would give an edge a 3rd face or a wrong direction
  size_t pinches = 0;                           ///< joins at a front vertex outside the pivot edge's fan
  size_t dropped_triangles = 0;                 ///< triangles dropped by mesh() at vertices still pinched
  std::vector<size_t> triangles_per_radius;     ///< triangles after each pass
  std::vector<double> seconds_per_radius;       ///< wall time of each pass [s] (with slabs: summed over slabs + seam)
  int regions = 1;                              ///< slabs meshed in parallel (1 = sequential)
  double region_seconds = 0.0;                  ///< wall time of the parallel slab phase [s]
  double seam_seconds = 0.0;                    ///< wall time of merging and stitching the seams [s]
  double mesh_seconds = 0.0;                    ///< wall time of mesh(): dropping pinched fans, building the mesh [s]
};

/// One Ball Pivoting surface on a fixed point set. Call pivot(r) with increasing radii.
class BallPivoting {
 public:
  /// points and normals have the same size; normals are unit vectors. Points whose position or
  /// normal is not finite (or whose normal is zero) never become vertices. Throws
  /// std::invalid_argument when the sizes differ or there are more than 2^31 points.
  BallPivoting(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals);
  ~BallPivoting();

  /// Runs one pass with ball radius radius_m [m] (> 0, not smaller than the previous pass): the
  /// existing boundary is re-activated, pivoted, and new seeds are searched until none is left.
  /// Throws std::invalid_argument for a bad radius.
  void pivot(double radius_m);

  /// Runs the passes for radii_m (increasing, as pivot()). On a fresh object with regions != 1 the
  /// points are cut into slabs meshed in parallel and stitched (see above); regions = 0 chooses
  /// automaticRegions(). After earlier pivot() calls, or with regions = 1, it is pivot() per radius.
  /// Throws std::invalid_argument for bad radii or regions < 0.
  void run(const std::vector<double>& radii_m, int regions = 0);

  /// The number of slabs run() uses by default for this many points: one per 500 000 points,
  /// 1 to 4 (small inputs stay sequential).
  static int automaticRegions(size_t points);

  /// Faces so far (indices into the input points), counter-clockwise seen from the normals' side.
  std::vector<Eigen::Vector3i> faces() const;
  const BpaStats& stats() const { return stats_; }

  /// The mesh with only the used points as vertices (with their normals); triangles of all but the
  /// largest fan at still pinched vertices are dropped, so it is a manifold.
  TriangleMesh mesh();

  /// Checks the internal front structure (loops closed, sizes, vertex links); returns an empty
  /// string or the first problem found. For tests; O(front).
  std::string checkFront() const;

 private:
  struct Edge {
    int a, b;                ///< directed a -> b, as in its triangle (a, b, opp)
    int opp;                 ///< third vertex of the triangle
    int next, prev;          ///< neighbours in the loop
    int loop;                ///< loop id
    Eigen::Vector3d center;  ///< ball centre of the triangle for the current radius
    int next_out;            ///< next front edge leaving the same vertex a (list per vertex), -1 at the end
    uint8_t state;           ///< see .cpp
  };

  /// A slab worker of `parent`: shares its points, grid and per-vertex arrays (its vertices are
  /// only those of its slab, so the workers write disjoint elements).
  BallPivoting(BallPivoting& parent, int region);

  /// Centre of the ball of the current radius on the side of triangle (a, b, c)'s normal; false
  /// when there is none (or, with check_normals, when a corner's normal disagrees).
  bool ballCenter(int a, int b, int c, Eigen::Vector3d& center, bool check_normals) const;
  bool ballEmpty(const Eigen::Vector3d& center, const std::vector<uint32_t>& candidates, int a, int b, int c) const;
  bool findSeed();
  void addSeed(int a, int b, int c, const Eigen::Vector3d& center);
  void pivotEdge(int e);
  void join(int e, int q, const Eigen::Vector3d& center);
  int findFront(int a, int b) const;
  void processActive();
  void glue(int e1, int e2);
  int newEdge(int a, int b, int opp, const Eigen::Vector3d& center, int loop);
  void removeEdge(int e);
  void relabel(int start, int loop);
  bool edgeUsed(int a, int b) const;
  void addFace(int a, int b, int c);
  /// One pass on the grid already set (grid_): re-activates the boundary edges that pass `activate`,
  /// pivots, and searches seeds among the points that pass seedable().
  void runPass(double radius_m, bool seam);
  bool mine(int v) const { return region_id_ < 0 || region_[v] == region_id_; }
  bool nearCut(int v) const;
  void runRegions(const std::vector<double>& radii_m, int regions);
  void merge(BallPivoting& child);
  void allocDirEdges(size_t keys);

  // Point data and per-vertex state in a spatially coherent order (Morton order of the points, so
  // that grid queries read nearby memory); perm_[internal] = input index. A slab worker points to
  // its parent's arrays.
  std::vector<int> perm_;
  std::vector<Eigen::Vector3d> p_store_, n_store_;
  std::vector<uint8_t> used_store_;
  std::vector<int> out_head_store_, front_deg_store_;
  size_t num_points_ = 0;
  const Eigen::Vector3d* p_ = nullptr;
  const Eigen::Vector3d* n_ = nullptr;
  uint8_t* used_ = nullptr;
  int* out_head_ = nullptr;   ///< first front edge leaving each vertex, -1 if none
  int* front_deg_ = nullptr;  ///< front edges leaving each vertex
  // Slabs: region of each point, the cuts along axis cut_axis_; region_id_ >= 0 in a slab worker.
  std::vector<uint8_t> region_store_;
  const uint8_t* region_ = nullptr;
  int region_id_ = -1;
  int cut_axis_ = 0;
  std::vector<double> cuts_;
  double seam_band_ = 0.0;  ///< > 0 in the seam phase: only edges and seeds this close to a cut [m]
  size_t seam_first_edge_ = 0;

  std::vector<Edge> edges_;
  std::vector<int> loop_size_;
  std::vector<int> active_;  ///< queue of edge ids (FIFO via head_)
  size_t head_ = 0;
  std::vector<Eigen::Vector3i> faces_;
  std::vector<int> pinched_;         ///< vertices that were pinched (some may have healed)
  std::vector<uint64_t> dir_edges_;  ///< hash set of directed edges (open addressing)
  size_t dir_edge_count_ = 0;
  double radius_ = 0.0;
  BpaStats stats_;
  // per pass
  std::unique_ptr<SpatialGrid> grid_store_;
  const SpatialGrid* grid_ = nullptr;
  size_t seed_cursor_ = 0;
  std::vector<uint32_t> scratch_;
  struct Candidate {
    double angle;
    int q;
    Eigen::Vector3d center;
    double dist2;  ///< squared distance of q to the pivot edge's midpoint (ties of the angle)
  };
  std::vector<Candidate> candidates_;
  struct LensPoint {
    Eigen::Vector3d p;
    double di2, dj2;  ///< squared distances to the pivot edge's end points
    int q;
  };
  std::vector<LensPoint> lens_;
  std::vector<std::pair<double, int>> seed_near_;
  bool insertDirEdge(uint64_t key);
  bool hasDirEdge(uint64_t key) const;
};

/// Convenience: runs the passes for the radii (increasing) and returns the mesh. points and normals
/// as for BallPivoting.
TriangleMesh ballPivot(const std::vector<Eigen::Vector3f>& points, const std::vector<Eigen::Vector3f>& normals,
                       const std::vector<double>& radii_m, BpaStats* stats = nullptr);

}  // namespace mesher
}  // namespace scanstop
