#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "scanstop_explorer/distance_transform.h"
#include "scenes.h"

using namespace scanstop::explorer;

namespace {
cv::Mat opencvDt(const cv::Mat& mask) {
  cv::Mat d;
  cv::distanceTransform(mask, d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  return d;
}

void expectEqualToOpenCv(const cv::Mat& mask, const std::string& what) {
  const cv::Mat ours = distanceTransform(mask), ref = opencvDt(mask);
  ASSERT_EQ(ours.size(), ref.size());
  int bad = 0;
  for (int r = 0; r < mask.rows; ++r)
    for (int c = 0; c < mask.cols; ++c)
      if (std::abs(ours.at<float>(r, c) - ref.at<float>(r, c)) > 1e-4f * std::max(1.0f, ref.at<float>(r, c)) &&
          bad++ < 5)
        ADD_FAILURE() << what << " at (" << c << ", " << r << "): ours " << ours.at<float>(r, c) << " opencv "
                      << ref.at<float>(r, c);
  EXPECT_EQ(bad, 0) << what;
}
}  // namespace

TEST(DistanceTransform, KnownValues) {
  // One background pixel in the middle of a 7 x 5 image: squared distances are dx^2 + dy^2.
  cv::Mat m = cv::Mat::ones(5, 7, CV_8U);
  m.at<uint8_t>(2, 3) = 0;
  const cv::Mat sq = squaredDistanceTransform(m);
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 7; ++c) EXPECT_EQ(sq.at<int>(r, c), (r - 2) * (r - 2) + (c - 3) * (c - 3));
}

TEST(DistanceTransform, OutsideIsNotBackgroundAndNoBackgroundIsFlagged) {
  cv::Mat m = cv::Mat::ones(4, 4, CV_8U);
  EXPECT_EQ(squaredDistanceTransform(m).at<int>(1, 1), kNoBackground);
  m.at<uint8_t>(0, 0) = 0;
  EXPECT_EQ(squaredDistanceTransform(m).at<int>(3, 3), 18);
}

TEST(DistanceTransform, EqualsOpenCvOnRandomGrids) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 90), h = 1 + static_cast<int>(rng() % 90);
    const double p_bg = std::uniform_real_distribution<double>(0.0005, 0.5)(rng);
    cv::Mat m(h, w, CV_8U);
    std::bernoulli_distribution bg(p_bg);
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) m.at<uint8_t>(r, c) = bg(rng) ? 0 : 1;
    m.at<uint8_t>(static_cast<int>(rng() % h), static_cast<int>(rng() % w)) = 0;  // at least one background pixel
    expectEqualToOpenCv(m, "random trial " + std::to_string(trial));
  }
}

TEST(DistanceTransform, EqualsOpenCvOnTestScenes) {
  using namespace scanstop::explorer::test;
  for (const auto& [name, scene] :
       {std::make_pair("corridor", corridor()), std::make_pair("two rooms", twoRooms()), std::make_pair("L", lShape()),
        std::make_pair("donut", donut()), std::make_pair("table", tableRoom())}) {
    expectEqualToOpenCv(scene.free, name);
    expectEqualToOpenCv(floorMask(idealStates(scene)), std::string(name) + " floor");
  }
}

TEST(DistanceTransform, RejectsWrongType) {
  EXPECT_THROW(squaredDistanceTransform(cv::Mat::ones(3, 3, CV_32F)), std::invalid_argument);
}
