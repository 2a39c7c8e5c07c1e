#include "scanstop_explorer/skeleton.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace scanstop {
namespace explorer {

const std::array<cv::Point, 8> kNeighbourOffsets = {cv::Point(1, 0),  cv::Point(1, 1),  cv::Point(0, 1),
                                                    cv::Point(-1, 1), cv::Point(-1, 0), cv::Point(-1, -1),
                                                    cv::Point(0, -1), cv::Point(1, -1)};

namespace {

inline bool bit(int code, int i) { return (code >> (i & 7)) & 1; }

int count4(int code) { return bit(code, 0) + bit(code, 2) + bit(code, 4) + bit(code, 6); }

bool simple4(int code) { return foregroundBranches(code) == 1 && backgroundComponents(code) == 1; }

std::array<uint8_t, 256> makeTable(bool (*f)(int)) {
  std::array<uint8_t, 256> t{};
  for (int c = 0; c < 256; ++c) t[c] = f(c) ? 1 : 0;
  return t;
}

inline int codeAt(const cv::Mat& img, int r, int c) {
  int code = 0;
  for (int i = 0; i < 8; ++i) {
    const int rr = r + kNeighbourOffsets[i].y, cc = c + kNeighbourOffsets[i].x;
    if (rr >= 0 && cc >= 0 && rr < img.rows && cc < img.cols && img.at<uint8_t>(rr, cc)) code |= 1 << i;
  }
  return code;
}

}  // namespace

int neighbourhoodCode(const cv::Mat& image, const cv::Point& p) { return codeAt(image, p.y, p.x); }

int foregroundBranches(int code) {
  // Ring neighbours i and i+1 are 4-adjacent; other ring pairs are not. A 4-component of the ring
  // is thus a circular run of set bits; it touches p 4-adjacently if it holds an even bit.
  if (code == 0xFF) return 1;
  int runs = 0;
  for (int i = 0; i < 8; ++i) {
    if (!bit(code, i) || bit(code, i - 1 + 8)) continue;  // start of a run
    bool touches = false;
    for (int j = i; bit(code, j); ++j) touches = touches || (j % 2 == 0);
    runs += touches ? 1 : 0;
  }
  return runs;
}

int backgroundComponents(int code) {
  // 8-adjacency on the ring: consecutive neighbours, plus two 4-neighbours around a corner.
  int parent[8];
  for (int i = 0; i < 8; ++i) parent[i] = i;
  auto find = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  auto unite = [&](int a, int b) { parent[find(a)] = find(b); };
  for (int i = 0; i < 8; ++i) {
    if (bit(code, i)) continue;
    if (!bit(code, i + 1)) unite(i, (i + 1) % 8);
    if (i % 2 == 0 && !bit(code, i + 2)) unite(i, (i + 2) % 8);
  }
  int n = 0;
  for (int i = 0; i < 8; ++i)
    if (!bit(code, i) && find(i) == i) ++n;
  return n;
}

const std::array<uint8_t, 256>& homotopyTable() {
  static const std::array<uint8_t, 256> t = makeTable([](int c) { return !simple4(c); });
  return t;
}

const std::array<uint8_t, 256>& pruningTable() {
  static const std::array<uint8_t, 256> t = makeTable([](int c) { return simple4(c) && count4(c) == 1; });
  return t;
}

const std::array<uint8_t, 256>& specialPointTable() {
  static const std::array<uint8_t, 256> t = makeTable([](int c) {
    const int branches = foregroundBranches(c);
    return branches == 0 || branches >= 3 || (branches == 1 && count4(c) == 1);
  });
  return t;
}

void thinPreservingEnds(cv::Mat& image, const cv::Mat& keep) {
  const auto& relevant = homotopyTable();
  bool changed = true;
  bool forward = true;
  while (changed) {
    changed = false;
    for (int k = 0; k < image.rows * image.cols; ++k) {
      const int idx = forward ? k : image.rows * image.cols - 1 - k;
      const int r = idx / image.cols, c = idx % image.cols;
      if (!image.at<uint8_t>(r, c) || (!keep.empty() && keep.at<uint8_t>(r, c))) continue;
      const int code = codeAt(image, r, c);
      if (!relevant[code] && count4(code) >= 2) {
        image.at<uint8_t>(r, c) = 0;
        changed = true;
      }
    }
    forward = !forward;
  }
}

cv::Mat findAnchors(const cv::Mat& sq_dt, const cv::Mat& mask) {
  if (sq_dt.type() != CV_32S || mask.type() != CV_8U || sq_dt.size() != mask.size())
    throw std::invalid_argument("findAnchors: need CV_32S sq_dt and CV_8U mask of one size");
  cv::Mat anchors = cv::Mat::zeros(mask.size(), CV_8U);
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c) {
      if (!mask.at<uint8_t>(r, c)) continue;
      const int v = sq_dt.at<int>(r, c);
      bool is_max = v > 0;
      for (int i = 0; i < 8 && is_max; ++i) {
        const int rr = r + kNeighbourOffsets[i].y, cc = c + kNeighbourOffsets[i].x;
        if (rr < 0 || cc < 0 || rr >= mask.rows || cc >= mask.cols || !mask.at<uint8_t>(rr, cc)) continue;
        if (sq_dt.at<int>(rr, cc) > v) is_max = false;
      }
      if (is_max) anchors.at<uint8_t>(r, c) = 1;
    }
  thinPreservingEnds(anchors);
  // One anchor per maximal disc: strongest first; a maximum inside a kept anchor's disc is dropped
  // (discretisation makes many weak maxima on the flanks of wide ridges and plateaus).
  std::vector<std::pair<int, cv::Point>> candidates;
  for (int r = 0; r < anchors.rows; ++r)
    for (int c = 0; c < anchors.cols; ++c)
      if (anchors.at<uint8_t>(r, c)) candidates.emplace_back(sq_dt.at<int>(r, c), cv::Point(c, r));
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  cv::Mat covered = cv::Mat::zeros(mask.size(), CV_8U);
  anchors.setTo(0);
  for (const auto& [sq, p] : candidates) {
    if (covered.at<uint8_t>(p)) continue;
    anchors.at<uint8_t>(p) = 1;
    const int radius = static_cast<int>(std::floor(std::sqrt(static_cast<double>(sq)))) - 1;
    if (radius > 0) cv::circle(covered, p, radius, cv::Scalar(1), cv::FILLED);
  }
  return anchors;
}

cv::Mat vincentSkeleton(const cv::Mat& mask, const cv::Mat& anchors, cv::Mat* after_propagation) {
  if (mask.type() != CV_8U || (!anchors.empty() && (anchors.type() != CV_8U || anchors.size() != mask.size())))
    throw std::invalid_argument("vincentSkeleton: need CV_8U mask and anchors of one size");
  const auto& relevant = homotopyTable();
  const auto& prunable = pruningTable();
  // Initialisation: anchors 1, other foreground 2, border pixels 3 and queued.
  cv::Mat I = cv::Mat::zeros(mask.size(), CV_8U);
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c)
      if (mask.at<uint8_t>(r, c)) I.at<uint8_t>(r, c) = (!anchors.empty() && anchors.at<uint8_t>(r, c)) ? 1 : 2;
  std::deque<cv::Point> fifo;
  for (int r = 0; r < I.rows; ++r)
    for (int c = 0; c < I.cols; ++c)
      if (I.at<uint8_t>(r, c) == 2 && codeAt(I, r, c) != 0xFF) {
        I.at<uint8_t>(r, c) = 3;
        fifo.emplace_back(c, r);
      }
  auto inside = [&](const cv::Point& p) { return p.x >= 0 && p.y >= 0 && p.x < I.cols && p.y < I.rows; };
  // Propagation.
  std::vector<cv::Point> tab;
  while (!fifo.empty()) {
    const cv::Point p = fifo.front();
    fifo.pop_front();
    for (const cv::Point& d : kNeighbourOffsets) {
      const cv::Point q = p + d;
      if (inside(q) && I.at<uint8_t>(q) == 2) {
        I.at<uint8_t>(q) = 3;
        fifo.push_back(q);
      }
    }
    if (relevant[codeAt(I, p.y, p.x)])
      tab.push_back(p);
    else
      I.at<uint8_t>(p) = 0;
  }
  if (after_propagation) *after_propagation = (I != 0) / 255;
  // Pruning.
  for (const cv::Point& p : tab)
    if (I.at<uint8_t>(p) == 3 && prunable[codeAt(I, p.y, p.x)]) {
      I.at<uint8_t>(p) = 2;
      fifo.push_back(p);
    }
  while (!fifo.empty()) {
    const cv::Point p = fifo.front();
    fifo.pop_front();
    if (I.at<uint8_t>(p) != 2) continue;
    if (prunable[codeAt(I, p.y, p.x)]) {
      I.at<uint8_t>(p) = 0;
      for (const cv::Point& d : kNeighbourOffsets) {
        const cv::Point q = p + d;
        if (inside(q) && I.at<uint8_t>(q) == 3) {
          I.at<uint8_t>(q) = 2;
          fifo.push_back(q);
        }
      }
    } else {
      I.at<uint8_t>(p) = 3;
    }
  }
  cv::Mat skeleton = (I != 0) / 255;
  thinPreservingEnds(skeleton, anchors);
  return skeleton;
}

std::vector<cv::Point> specialPoints(const cv::Mat& skeleton) {
  const auto& special = specialPointTable();
  std::vector<cv::Point> out;
  for (int r = 0; r < skeleton.rows; ++r)
    for (int c = 0; c < skeleton.cols; ++c)
      if (skeleton.at<uint8_t>(r, c) && special[codeAt(skeleton, r, c)]) out.emplace_back(c, r);
  return out;
}

Topology topology(const cv::Mat& mask) {
  cv::Mat padded;
  cv::copyMakeBorder(mask != 0, padded, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat labels;
  Topology t;
  t.components = cv::connectedComponents(padded, labels, 4, CV_32S) - 1;
  t.holes = cv::connectedComponents(padded == 0, labels, 8, CV_32S) - 2;
  return t;
}

}  // namespace explorer
}  // namespace scanstop
