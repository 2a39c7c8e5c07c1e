#include <gtest/gtest.h>

#include <random>

#include "scanstop_explorer/distance_transform.h"
#include "scanstop_explorer/skeleton.h"
#include "scenes.h"

using namespace scanstop::explorer;

namespace {
/// 3 x 3 image of a neighbourhood code around a set centre pixel.
cv::Mat patch(int code) {
  cv::Mat m = cv::Mat::zeros(3, 3, CV_8U);
  m.at<uint8_t>(1, 1) = 1;
  for (int i = 0; i < 8; ++i)
    if (code & (1 << i)) m.at<uint8_t>(cv::Point(1, 1) + kNeighbourOffsets[i]) = 1;
  return m;
}
int rotate90(int code) { return ((code << 2) | (code >> 6)) & 0xFF; }
int mirror(int code) {  // x -> -x: E<->W, NE<->NW, SE<->SW
  const int map[8] = {4, 3, 2, 1, 0, 7, 6, 5};
  int out = 0;
  for (int i = 0; i < 8; ++i)
    if (code & (1 << i)) out |= 1 << map[i];
  return out;
}
constexpr int E = 1, NE = 2, N = 4, NW = 8, W = 16, SW = 32, S = 64, SE = 128;
}  // namespace

TEST(SkeletonTables, NeighbourhoodCodeMatchesBitOrder) {
  for (int code = 0; code < 256; ++code) EXPECT_EQ(neighbourhoodCode(patch(code), {1, 1}), code);
}

TEST(SkeletonTables, KnownConfigurations) {
  const auto& h = homotopyTable();
  const auto& p = pruningTable();
  const auto& s = specialPointTable();
  EXPECT_TRUE(h[0]);                          // isolated pixel: removing it deletes a component
  EXPECT_TRUE(h[0xFF]);                       // interior pixel: removing it makes a hole
  EXPECT_TRUE(h[NE]);                         // only a diagonal neighbour: not 4-connected, still a component
  EXPECT_FALSE(h[N]);                         // end of a line
  EXPECT_TRUE(h[N | S]);                      // middle of a line
  EXPECT_TRUE(h[N | E]);                      // staircase corner of a 4-connected line
  EXPECT_FALSE(h[N | NE | E]);                // bump on a corner: redundant
  EXPECT_TRUE(h[N | E | S]);                  // T junction
  EXPECT_FALSE(h[E | NE | N | NW | W]);       // edge of a half plane
  EXPECT_TRUE(h[NE | N | NW | SW | S | SE]);  // between two walls (E and W background)

  EXPECT_TRUE(p[N]);
  EXPECT_TRUE(p[N | NE]);
  EXPECT_TRUE(p[N | NE | NW]);
  EXPECT_FALSE(p[0]);
  EXPECT_FALSE(p[N | S]);
  EXPECT_FALSE(p[N | NE | E]);  // two 4-neighbours: not a free end
  EXPECT_FALSE(p[E | NE | N | NW | W]);

  EXPECT_TRUE(s[0]);              // isolated
  EXPECT_TRUE(s[N]);              // end
  EXPECT_FALSE(s[N | S]);         // line
  EXPECT_FALSE(s[N | E]);         // corner
  EXPECT_TRUE(s[N | E | S]);      // junction
  EXPECT_TRUE(s[N | E | S | W]);  // crossing
}

TEST(SkeletonTables, InvariantUnderRotationAndMirror) {
  for (int code = 0; code < 256; ++code)
    for (const int other : {rotate90(code), mirror(code)}) {
      EXPECT_EQ(homotopyTable()[code], homotopyTable()[other]) << code;
      EXPECT_EQ(pruningTable()[code], pruningTable()[other]) << code;
      EXPECT_EQ(specialPointTable()[code], specialPointTable()[other]) << code;
    }
}

TEST(SkeletonTables, PrunableImpliesNotRelevant) {
  for (int code = 0; code < 256; ++code)
    if (pruningTable()[code]) {
      EXPECT_FALSE(homotopyTable()[code]) << code;
    }
}

// A pixel is homotopy relevant exactly when removing it changes the number of 4-components or of
// holes of its 5 x 5 surroundings (checked on every 3 x 3 pattern embedded with a background ring).
TEST(SkeletonTables, HomotopyTableMatchesTopologyChange) {
  int relevant = 0;
  for (int code = 0; code < 256; ++code) {
    cv::Mat img = cv::Mat::zeros(5, 5, CV_8U);
    patch(code).copyTo(img(cv::Rect(1, 1, 3, 3)));
    const Topology before = topology(img);
    img.at<uint8_t>(2, 2) = 0;
    const Topology after = topology(img);
    const bool changes = before.components != after.components || before.holes != after.holes;
    EXPECT_EQ(static_cast<bool>(homotopyTable()[code]), changes) << "code " << code;
    relevant += changes;
  }
  EXPECT_GT(relevant, 0);
  EXPECT_LT(relevant, 256);
}

TEST(SkeletonTables, RemovingSimplePixelsKeepsTopologyOfRandomImages) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 40; ++trial) {
    cv::Mat img(24, 24, CV_8U);
    for (int r = 0; r < img.rows; ++r)
      for (int c = 0; c < img.cols; ++c) img.at<uint8_t>(r, c) = (rng() % 100) < 60 ? 1 : 0;
    const Topology t0 = topology(img);
    for (int k = 0; k < 200; ++k) {
      const cv::Point p(static_cast<int>(rng() % 24), static_cast<int>(rng() % 24));
      if (img.at<uint8_t>(p) && !homotopyTable()[neighbourhoodCode(img, p)]) img.at<uint8_t>(p) = 0;
    }
    const Topology t1 = topology(img);
    EXPECT_EQ(t0.components, t1.components);
    EXPECT_EQ(t0.holes, t1.holes);
  }
}

namespace {
struct Named {
  const char* name;
  test::Scene scene;
  int components;
  int holes;
};
std::vector<Named> scenes() {
  return {{"corridor", test::corridor(), 1, 0},
          {"two rooms", test::twoRooms(), 1, 0},
          {"L", test::lShape(), 1, 0},
          {"donut", test::donut(), 1, 1},
          {"table", test::tableRoom(), 1, 4}};
}
cv::Mat accessibleOf(const test::Scene& s, cv::Mat* sq = nullptr) {
  const cv::Mat d = squaredDistanceTransform(floorMask(test::idealStates(s)));
  if (sq) *sq = d;
  return accessibleFloor(d, 0.3 / 0.05);
}
}  // namespace

TEST(Skeleton, KeepsComponentsAndHolesOfTheAccessibleFloor) {
  for (const Named& n : scenes()) {
    cv::Mat sq;
    const cv::Mat acc = accessibleOf(n.scene, &sq);
    const Topology ta = topology(acc);
    EXPECT_EQ(ta.components, n.components) << n.name;
    EXPECT_EQ(ta.holes, n.holes) << n.name;
    const cv::Mat anchors = findAnchors(sq, acc);
    cv::Mat unpruned;
    const cv::Mat skel = vincentSkeleton(acc, anchors, &unpruned);
    const Topology ts = topology(skel), tu = topology(unpruned);
    EXPECT_EQ(ts.components, ta.components) << n.name;
    EXPECT_EQ(ts.holes, ta.holes) << n.name;
    EXPECT_EQ(tu.components, ta.components) << n.name;
    EXPECT_EQ(tu.holes, ta.holes) << n.name;
    // The skeleton is thin, inside the floor, keeps every anchor and pruning removed spurs.
    EXPECT_EQ(cv::countNonZero(skel & (acc == 0)), 0) << n.name;
    EXPECT_EQ(cv::countNonZero(anchors & (skel == 0)), 0) << n.name;
    EXPECT_LE(cv::countNonZero(skel), cv::countNonZero(unpruned)) << n.name;
    EXPECT_LT(cv::countNonZero(skel), cv::countNonZero(acc) / 5) << n.name;
    EXPECT_GT(cv::countNonZero(anchors), 0) << n.name;
  }
}

TEST(Skeleton, RingSkeletonIsALoopWithoutEnds) {
  // A 1-pixel-free ring band without anchors shrinks to a closed loop: no end points.
  cv::Mat ring = cv::Mat::zeros(40, 40, CV_8U);
  cv::rectangle(ring, cv::Rect(5, 5, 30, 30), cv::Scalar(1), cv::FILLED);
  cv::rectangle(ring, cv::Rect(12, 12, 16, 16), cv::Scalar(0), cv::FILLED);
  const cv::Mat skel = vincentSkeleton(ring, cv::Mat());
  EXPECT_EQ(topology(skel).holes, 1);
  EXPECT_EQ(topology(skel).components, 1);
  for (const cv::Point& p : specialPoints(skel))
    ADD_FAILURE() << "unexpected special point (" << p.x << ", " << p.y << ")";
  // A simply connected blob without anchors prunes to a single pixel.
  cv::Mat blob = cv::Mat::zeros(20, 20, CV_8U);
  cv::rectangle(blob, cv::Rect(3, 4, 12, 9), cv::Scalar(1), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(vincentSkeleton(blob, cv::Mat())), 1);
}

TEST(Skeleton, BarBetweenTwoAnchorsIsALineWithTwoEnds) {
  cv::Mat bar = cv::Mat::zeros(11, 40, CV_8U);
  cv::rectangle(bar, cv::Rect(2, 2, 36, 7), cv::Scalar(1), cv::FILLED);
  cv::Mat anchors = cv::Mat::zeros(bar.size(), CV_8U);
  anchors.at<uint8_t>(5, 6) = 1;
  anchors.at<uint8_t>(5, 33) = 1;
  const cv::Mat skel = vincentSkeleton(bar, anchors);
  EXPECT_EQ(cv::countNonZero(skel), 28);  // the straight line between them
  const std::vector<cv::Point> sp = specialPoints(skel);
  ASSERT_EQ(sp.size(), 2u);
  EXPECT_EQ(sp[0], cv::Point(6, 5));
  EXPECT_EQ(sp[1], cv::Point(33, 5));
}

TEST(Skeleton, AnchorsAreLocalMaximaOfTheDistance) {
  cv::Mat m = cv::Mat::zeros(21, 21, CV_8U);
  cv::rectangle(m, cv::Rect(2, 2, 17, 17), cv::Scalar(1), cv::FILLED);
  const cv::Mat sq = squaredDistanceTransform(m);
  const cv::Mat a = findAnchors(sq, m);
  ASSERT_EQ(cv::countNonZero(a), 1);
  EXPECT_EQ(a.at<uint8_t>(10, 10), 1);  // the centre of the square
}
