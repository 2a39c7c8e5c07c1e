// Greedy set cover and the exact pair check on small instances with known optima.
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "scanstop_eval/set_cover.h"

using namespace scanstop::eval;

TEST(SetCover, GreedyPicksTheLargestGainFirstAndStopsWhenNothingIsLeft) {
  const std::vector<ElementSet> sets = {{0, 1}, {0, 1, 2, 3}, {3, 4}, {4}, {}};
  const GreedyCover g = greedyCover(sets, 6);  // element 5: no set has it
  ASSERT_EQ(g.order, (std::vector<size_t>{1, 2}));
  EXPECT_EQ(g.covered, (std::vector<size_t>{4, 5}));
}

TEST(SetCover, TiesGoToTheLowerIndex) {
  const GreedyCover g = greedyCover({{2, 3}, {0, 1}, {0, 1, 2, 3}}, 4);
  ASSERT_EQ(g.order, (std::vector<size_t>{2}));
  const GreedyCover h = greedyCover({{2, 3}, {0, 1}}, 4);
  EXPECT_EQ(h.order, (std::vector<size_t>{0, 1}));
}

TEST(SetCover, ThePairCheckFindsTheOptimumTheGreedyMisses) {
  // The classic trap: the middle set is largest, so the greedy takes it and then needs both halves'
  // remainders; the two halves alone cover everything.
  const std::vector<ElementSet> sets = {{0, 1, 2, 3, 4, 5, 6}, {7, 8, 9, 10, 11, 12, 13}, {0, 1, 2, 3, 7, 8, 9, 10}};
  const GreedyCover g = greedyCover(sets, 14);
  ASSERT_EQ(g.order.size(), 3u);
  EXPECT_EQ(g.order[0], 2u);
  const std::vector<CoverTarget> greedy_only = scansNeeded(g, 14, {0.5, 1.0}, std::nullopt);
  EXPECT_EQ(*greedy_only[0].scans, 1u);  // 8 of 14
  EXPECT_TRUE(greedy_only[0].optimal);
  EXPECT_EQ(*greedy_only[1].scans, 3u);
  EXPECT_FALSE(greedy_only[1].optimal);
  const std::optional<size_t> pair = bestPairCoverage(sets, 14);
  ASSERT_TRUE(pair);
  EXPECT_EQ(*pair, 14u);
  const std::vector<CoverTarget> t = scansNeeded(g, 14, {0.5, 1.0}, pair);
  EXPECT_EQ(*t[1].scans, 2u);
  EXPECT_TRUE(t[1].optimal);
}

TEST(SetCover, ThreeIsOptimalWhenNoPairReachesAndUnreachableSharesHaveNoCount) {
  const std::vector<ElementSet> sets = {{0, 1}, {2, 3}, {4, 5}};
  const GreedyCover g = greedyCover(sets, 7);
  const std::vector<CoverTarget> t = scansNeeded(g, 7, {0.85, 0.9}, bestPairCoverage(sets, 7));
  EXPECT_EQ(*t[0].scans, 3u);  // 6 of 7 = 0.857
  EXPECT_TRUE(t[0].optimal);
  EXPECT_FALSE(t[1].scans);  // element 6 is in no set
}

TEST(SetCover, BadIdsAndTooMuchWorkAreSaidSo) {
  EXPECT_THROW(greedyCover({{0, 4}}, 4), std::invalid_argument);
  EXPECT_FALSE(bestPairCoverage({{0}, {1}, {2}}, 1000000, 10.0));
  EXPECT_EQ(*bestPairCoverage({{0, 1, 2}}, 3), 3u);
}
