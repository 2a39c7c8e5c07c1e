#include "scanstop_explorer/distance_transform.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace scanstop {
namespace explorer {

namespace {

// Meijster, Roerdink, Hesselink: "A general algorithm for computing distance transforms in linear
// time" (2000). Phase 1: per column, distance to the nearest background pixel in that column
// (done with two row-wise sweeps so memory is read sequentially). Phase 2: per row, the lower
// envelope of the parabolas (x - i)^2 + g(i)^2. `emit(row, x, squared_distance)` stores results.
template <typename Emit>
bool meijster(const cv::Mat& mask, Emit emit) {
  if (mask.type() != CV_8U) throw std::invalid_argument("distance transform: mask must be CV_8U");
  const int w = mask.cols, h = mask.rows;
  if (static_cast<long>(w) + h > 20000)
    throw std::invalid_argument("distance transform: image larger than 20000 pixels");
  const int inf = w + h + 1;  // larger than any in-image distance
  std::vector<int> g(static_cast<size_t>(w) * h);
  for (int x = 0; x < w; ++x) g[x] = mask.at<uint8_t>(0, x) ? inf : 0;
  for (int y = 1; y < h; ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    int* gy = &g[static_cast<size_t>(y) * w];
    const int* gp = gy - w;
    for (int x = 0; x < w; ++x) gy[x] = m[x] ? std::min(inf, gp[x] + 1) : 0;
  }
  for (int y = h - 2; y >= 0; --y) {
    int* gy = &g[static_cast<size_t>(y) * w];
    const int* gn = gy + w;
    for (int x = 0; x < w; ++x) gy[x] = std::min(gy[x], gn[x] + 1);
  }
  std::vector<int> s(w), t(w), g2(w);
  bool any_background = false;
  for (int y = 0; y < h; ++y) {
    const int* gy = &g[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) g2[x] = gy[x] * gy[x];
    int q = 0;
    s[0] = 0;
    t[0] = 0;
    for (int u = 1; u < w; ++u) {
      const int gu = g2[u];
      while (q >= 0) {
        const int dt = t[q] - s[q], du = t[q] - u;
        if (dt * dt + g2[s[q]] <= du * du + gu) break;
        --q;
      }
      if (q < 0) {
        q = 0;
        s[0] = u;
      } else {
        const int i = s[q];
        const long num = static_cast<long>(u) * u - static_cast<long>(i) * i + gu - g2[i];
        const long den = 2L * (u - i);
        const long sep = num >= 0 ? num / den : -((-num + den - 1) / den);  // floor division
        if (sep + 1 < w) {
          ++q;
          s[q] = u;
          t[q] = static_cast<int>(sep + 1);
        }
      }
    }
    const long lim = static_cast<long>(inf) * inf;
    for (int u = w - 1; u >= 0; --u) {
      const int du = u - s[q];
      const int d = du * du + g2[s[q]];
      if (d < lim) any_background = true;
      emit(y, u, d);
      if (u == t[q]) --q;
    }
  }
  return any_background;
}

}  // namespace

cv::Mat squaredDistanceTransform(const cv::Mat& mask) {
  cv::Mat out(mask.size(), CV_32S);
  const bool any = meijster(mask, [&](int y, int x, int d) { out.ptr<int>(y)[x] = d; });
  if (!any) out.setTo(kNoBackground);
  return out;
}

cv::Mat distanceTransform(const cv::Mat& mask) {
  cv::Mat out(mask.size(), CV_32F);
  const bool any =
      meijster(mask, [&](int y, int x, int d) { out.ptr<float>(y)[x] = std::sqrt(static_cast<float>(d)); });
  if (!any) out.setTo(std::sqrt(static_cast<float>(kNoBackground)));
  return out;
}

}  // namespace explorer
}  // namespace scanstop
