#pragma once
/// Exact Euclidean distance transform in linear time (Meijster, Roerdink and Hesselink 2000; the
/// same two-pass separable scheme as Saito and Toriwaki, thesis 5.2).

#include <opencv2/core.hpp>

namespace scanstop {
namespace explorer {

/// Squared distance [cells^2] of every non-zero pixel of `mask` (CV_8U) to the centre of the
/// nearest zero pixel; zero pixels get 0. Pixels outside the image are not background. When the
/// image has no zero pixel at all, every value is kNoBackground. Returns CV_32S.
cv::Mat squaredDistanceTransform(const cv::Mat& mask);
/// sqrt of squaredDistanceTransform [cells], CV_32F; equals cv::distanceTransform(mask, DIST_L2,
/// DIST_MASK_PRECISE) whenever the image has a zero pixel.
cv::Mat distanceTransform(const cv::Mat& mask);

/// Value of squaredDistanceTransform when there is no background pixel.
constexpr int kNoBackground = 1 << 30;

}  // namespace explorer
}  // namespace scanstop
