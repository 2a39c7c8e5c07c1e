#include "scanstop_explorer/distance_transform.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace scanstop {
namespace explorer {

// Meijster, Roerdink, Hesselink: "A general algorithm for computing distance transforms in linear
// time" (2000). Phase 1: per column, distance to the nearest background pixel in that column.
// Phase 2: per row, lower envelope of the parabolas (x - i)^2 + g(i)^2.
cv::Mat squaredDistanceTransform(const cv::Mat& mask) {
  if (mask.type() != CV_8U) throw std::invalid_argument("squaredDistanceTransform: mask must be CV_8U");
  const int w = mask.cols, h = mask.rows;
  cv::Mat out(h, w, CV_32S);
  if (w == 0 || h == 0) return out;
  const long inf = static_cast<long>(w) + h + 1;  // larger than any in-image distance
  std::vector<long> g(static_cast<size_t>(w) * h);
  // Phase 1 (row-wise sweeps keep memory access sequential).
  for (int x = 0; x < w; ++x) g[x] = mask.at<uint8_t>(0, x) ? inf : 0;
  for (int y = 1; y < h; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    long* gy = &g[static_cast<size_t>(y) * w];
    const long* gp = gy - w;
    for (int x = 0; x < w; ++x) gy[x] = m[x] ? std::min(inf, gp[x] + 1) : 0;
  }
  for (int y = h - 2; y >= 0; --y) {
    long* gy = &g[static_cast<size_t>(y) * w];
    const long* gn = gy + w;
    for (int x = 0; x < w; ++x)
      if (gn[x] + 1 < gy[x]) gy[x] = gn[x] + 1;
  }
  // Phase 2.
  std::vector<int> s(w), t(w);
  std::vector<long> g2(w);
  bool any_background = false;
  for (int y = 0; y < h; ++y) {
    const long* gy = &g[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) g2[x] = gy[x] * gy[x];
    int q = 0;
    s[0] = 0;
    t[0] = 0;
    auto f = [&](long x, int i) { return (x - i) * (x - i) + g2[i]; };
    auto sep = [&](int i, int u) {
      const long num = static_cast<long>(u) * u - static_cast<long>(i) * i + g2[u] - g2[i];
      const long den = 2L * (u - i);
      return num >= 0 ? num / den : -((-num + den - 1) / den);  // floor division
    };
    for (int u = 1; u < w; ++u) {
      while (q >= 0 && f(t[q], s[q]) > f(t[q], u)) --q;
      if (q < 0) {
        q = 0;
        s[0] = u;
      } else {
        const long wv = 1 + sep(s[q], u);
        if (wv < w) {
          ++q;
          s[q] = u;
          t[q] = static_cast<int>(wv);
        }
      }
    }
    int* o = out.ptr<int>(y);
    for (int u = w - 1; u >= 0; --u) {
      const long d = f(u, s[q]);
      if (d < inf * inf) any_background = true;
      o[u] = static_cast<int>(std::min<long>(d, kNoBackground));
      if (u == t[q]) --q;
    }
  }
  if (!any_background) out.setTo(kNoBackground);
  return out;
}

cv::Mat distanceTransform(const cv::Mat& mask) {
  const cv::Mat sq = squaredDistanceTransform(mask);
  cv::Mat out(sq.size(), CV_32F);
  for (int y = 0; y < sq.rows; ++y) {
    const int* s = sq.ptr<int>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < sq.cols; ++x) o[x] = std::sqrt(static_cast<float>(s[x]));
  }
  return out;
}

}  // namespace explorer
}  // namespace scanstop
