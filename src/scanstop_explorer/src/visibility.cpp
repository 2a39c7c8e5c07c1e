#include "scanstop_explorer/visibility.h"

#include <cmath>
#include <stdexcept>

namespace scanstop {
namespace explorer {

RayCaster::RayCaster(const cv::Mat& states, const GridGeometry& geometry, double range_m, double spacing_cells)
    : states_(states), geometry_(geometry) {
  if (states.type() != CV_8U || states.cols != geometry.width || states.rows != geometry.height)
    throw std::invalid_argument("RayCaster: states must be CV_8U of the geometry's size");
  if (!(range_m > 0.0) || !(spacing_cells > 0.0))
    throw std::invalid_argument("RayCaster: range and ray spacing must be positive");
  const double r = range_m / geometry.resolution;  // [cells]
  const int n = std::max(8, static_cast<int>(std::ceil(2.0 * M_PI * r / spacing_cells)));
  ends_.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    const cv::Point e(static_cast<int>(std::lround(r * std::cos(a))), static_cast<int>(std::lround(r * std::sin(a))));
    if (ends_.empty() || ends_.back() != e) ends_.push_back(e);
  }
  stamp_ = cv::Mat::zeros(states.size(), CV_32S);
}

cv::Mat visibilityKnowledgeMap(const cv::Mat& states, const GridGeometry& g, const std::vector<Eigen::Vector2d>& scans,
                               double range_m) {
  cv::Mat k = cv::Mat::zeros(g.height, g.width, CV_32F);
  if (states.empty()) return k;
  RayCaster caster(states, g, range_m);
  for (const Eigen::Vector2d& s : scans) caster.cast(s, [&](const cv::Point& p) { k.at<float>(p) += 1.0f; });
  return k;
}

cv::Mat gainMap(const cv::Mat& states, const GridGeometry& g, const cv::Mat& knowledge, double knowledge_threshold,
                const cv::Mat& candidates, double range_m, int sample_cells, int max_samples, cv::Mat* sampled) {
  if (states.empty())
    return gainMap(states, g, cv::Mat(), cv::Mat(), candidates, range_m, sample_cells, max_samples, sampled);
  // The cells a scan would add something on: unknown, or not an obstacle and below the threshold.
  const cv::Mat worth = (states == kUnknown) | ((states != kObstacle) & (knowledge < knowledge_threshold));
  return gainMap(states, g, worth, cv::Mat(), candidates, range_m, sample_cells, max_samples, sampled);
}

cv::Mat gainMap(const cv::Mat& states, const GridGeometry& g, const cv::Mat& given_worth, const cv::Mat& required,
                const cv::Mat& candidates, double range_m, int sample_cells, int max_samples, cv::Mat* sampled) {
  cv::Mat gain = cv::Mat::zeros(g.height, g.width, CV_32F);
  cv::Mat lattice = cv::Mat::zeros(g.height, g.width, CV_8U);
  if (!states.empty() && cv::countNonZero(candidates) > 0) {
    int step = std::max(1, sample_cells);
    const auto samples = [&](int s) {
      int n = 0;
      for (int r = 0; r < candidates.rows; r += s)
        for (int c = 0; c < candidates.cols; c += s) n += candidates.at<uint8_t>(r, c) != 0;
      return n;
    };
    while (samples(step) > std::max(1, max_samples)) ++step;
    const cv::Mat worth = given_worth & (states != kObstacle);
    RayCaster caster(states, g, range_m, 1.0);  // a gain estimate: rays one cell apart at the range's end
    for (int r = 0; r < candidates.rows; r += step)
      for (int c = 0; c < candidates.cols; c += step) {
        if (!candidates.at<uint8_t>(r, c)) continue;
        lattice.at<uint8_t>(r, c) = 1;
        int n = 0;
        bool sees_required = required.empty();
        caster.cast(g.center({c, r}), [&](const cv::Point& p) {
          n += worth.at<uint8_t>(p) != 0;
          sees_required = sees_required || required.at<uint8_t>(p) != 0;
        });
        gain.at<float>(r, c) = sees_required ? static_cast<float>(n * g.cellArea()) : 0.0f;
      }
  }
  if (sampled) *sampled = lattice;
  return gain;
}

}  // namespace explorer
}  // namespace scanstop
