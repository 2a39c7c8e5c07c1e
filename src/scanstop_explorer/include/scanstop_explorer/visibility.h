#pragma once
/// What a scan sees on the floor grid, and what a scan from a candidate spot would add (issue #19
/// points 2 and 3). The thesis' knowledge map (5.4) gives every cell within k_r of a scan the same
/// credit, seen or hidden behind a cabinet; it also says the definition "is in principle
/// arbitrary". Here a scan's knowledge goes to the cells in plain sight of it: rays from the scan's
/// cell over the grid, stopped by obstacle cells, limited by a range. The same rays from a candidate
/// spot count what a scan there would add (expected gain): unknown cells and floor cells that still
/// lack knowledge. ROS-free.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <vector>

#include "scanstop_explorer/floor_map.h"
#include "scanstop_explorer/grid.h"

namespace scanstop {
namespace explorer {

/// Casts rays over a CellState grid from a point: every cell a 4-connected line from the point's
/// cell reaches before an obstacle cell, within `range_m`, once per cast. Unknown cells do not stop
/// a ray (what lies there was not seen, but nothing known blocks the view); obstacle cells do (and
/// are not reported). Rays: one per `spacing_cells` of arc at the range's end (so neighbouring rays
/// are at most that far apart anywhere within the range).
class RayCaster {
 public:
  RayCaster(const cv::Mat& states, const GridGeometry& geometry, double range_m, double spacing_cells = 0.5);

  /// Calls visit(cell) for every cell in sight of `from` (map frame [m]), each cell once. Nothing
  /// when `from` lies outside the grid or in an obstacle cell.
  template <class Visit>
  void cast(const Eigen::Vector2d& from, Visit&& visit);

  int rays() const { return static_cast<int>(ends_.size()); }

 private:
  const cv::Mat& states_;
  GridGeometry geometry_;
  std::vector<cv::Point> ends_;  ///< ray ends relative to the origin cell [cells]
  cv::Mat stamp_;                ///< CV_32S: the cast that last reached a cell
  int cast_ = 0;
};

/// Knowledge from visibility: each scan position adds 1 to every cell in its plain sight within
/// range_m (RayCaster). CV_32F. Positions outside the grid add nothing.
cv::Mat visibilityKnowledgeMap(const cv::Mat& states, const GridGeometry& geometry,
                               const std::vector<Eigen::Vector2d>& scan_positions, double range_m);

/// Expected gain of a scan [m^2]: the area of the cells in plain sight within range_m that are
/// unknown or lack knowledge (knowledge < knowledge_threshold; obstacle cells never count), for the
/// cells of `candidates` (CV_8U) on a lattice of `sample_cells` (rows and columns divisible by it;
/// the lattice is made coarser until at most max_samples cells remain). CV_32F, 0 elsewhere;
/// `sampled` (optional) receives the lattice cells (CV_8U 0/1).
cv::Mat gainMap(const cv::Mat& states, const GridGeometry& geometry, const cv::Mat& knowledge,
                double knowledge_threshold, const cv::Mat& candidates, double range_m, int sample_cells,
                int max_samples, cv::Mat* sampled = nullptr);
/// The same with the cells that count given (`worth`, CV_8U: a cell in sight adds its area when
/// set and not an obstacle); with `required` (CV_8U, may be empty) a candidate that has none of
/// its cells in sight gains nothing.
cv::Mat gainMap(const cv::Mat& states, const GridGeometry& geometry, const cv::Mat& worth, const cv::Mat& required,
                const cv::Mat& candidates, double range_m, int sample_cells, int max_samples,
                cv::Mat* sampled = nullptr);

// ---- implementation ------------------------------------------------------------------------

template <class Visit>
void RayCaster::cast(const Eigen::Vector2d& from, Visit&& visit) {
  const cv::Point o = geometry_.cellOf(from.x(), from.y());
  if (!geometry_.contains(o) || states_.at<uint8_t>(o) == kObstacle) return;
  if (++cast_ == 0) {  // the stamp wrapped: start over
    stamp_.setTo(0);
    cast_ = 1;
  }
  stamp_.at<int>(o) = cast_;
  visit(o);
  for (const cv::Point& d : ends_) {
    cv::LineIterator it(states_, o, o + d, 4);  // clipped to the grid
    ++it;                                       // the origin: done
    for (int k = 1; k < it.count; ++k, ++it) {
      const cv::Point p = it.pos();
      if (states_.at<uint8_t>(p) == kObstacle) break;
      int& s = stamp_.at<int>(p);
      if (s == cast_) continue;
      s = cast_;
      visit(p);
    }
  }
}

}  // namespace explorer
}  // namespace scanstop
