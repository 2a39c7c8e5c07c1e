#pragma once
/// Homotopy-preserving skeleton after L. Vincent, adapted to the rectangular grid with
/// 4-connected foreground and 8-connected background (thesis 5.3, figures 5.3-5.7).
///
/// Neighbourhood code of a pixel p: bit i is set when neighbour i is foreground, neighbours in
/// counter-clockwise order starting east (x = column + 1), y = row + 1 being "north":
///   bit 0 E, 1 NE, 2 N, 3 NW, 4 W, 5 SW, 6 S, 7 SE.

#include <array>
#include <opencv2/core.hpp>
#include <vector>

namespace scanstop {
namespace explorer {

/// Offsets (dx = column, dy = row) of the neighbours in bit order.
extern const std::array<cv::Point, 8> kNeighbourOffsets;

/// Neighbourhood code of pixel `p` in a CV_8U image (non-zero = foreground; outside = background).
int neighbourhoodCode(const cv::Mat& image, const cv::Point& p);

/// Number of 4-connected foreground components in the 8-neighbourhood that touch p 4-adjacently.
int foregroundBranches(int code);
/// Number of 8-connected background components in the 8-neighbourhood (all touch p).
int backgroundComponents(int code);

/// Homotopy table (figure 5.3): 1 when the centre pixel is relevant for the homotopy, i.e. not
/// 4-simple: removing it would split or delete a foreground component or create/merge a hole.
const std::array<uint8_t, 256>& homotopyTable();
/// Pruning table (figure 5.4): 1 when the centre pixel is the free end of a branch (simple and
/// exactly one 4-neighbour in the foreground) and may be pruned.
const std::array<uint8_t, 256>& pruningTable();
/// Special-point table (figure 5.7): 1 when the centre pixel of a thin skeleton is an end, a
/// junction or an isolated point (foregroundBranches != 2).
const std::array<uint8_t, 256>& specialPointTable();

/// Anchor pixels (CV_8U 0/1): local maxima of the squared distance transform `sq_dt` (CV_32S)
/// over the foreground of `mask` (no 8-neighbour in the mask is larger), one per maximal disc:
/// taken strongest first, a maximum lying inside the disc (radius - 1 cell) of a kept anchor is
/// dropped, so plateaus and the many weak maxima of wide ridges give few anchors.
cv::Mat findAnchors(const cv::Mat& sq_dt, const cv::Mat& mask);

/// Removes 4-simple pixels that are not branch ends, in raster sweeps until nothing changes; pixels
/// set in `keep` (may be empty) stay. Keeps the homotopy; used to thin plateaus and skeletons.
void thinPreservingEnds(cv::Mat& image, const cv::Mat& keep = cv::Mat());

/// Vincent's skeleton of `mask` (CV_8U, non-zero = foreground) keeping `anchors`:
/// initialisation, propagation with the homotopy table, pruning with the pruning table.
/// Returns CV_8U 0/1. `after_propagation`, when given, receives the skeleton before pruning.
cv::Mat vincentSkeleton(const cv::Mat& mask, const cv::Mat& anchors, cv::Mat* after_propagation = nullptr);

/// Special points (specialPointTable) of a skeleton image, in raster order.
std::vector<cv::Point> specialPoints(const cv::Mat& skeleton);

/// Number of 4-connected foreground components and of holes (8-connected background components
/// not touching the image border) of a CV_8U image.
struct Topology {
  int components = 0;
  int holes = 0;
};
Topology topology(const cv::Mat& mask);

}  // namespace explorer
}  // namespace scanstop
