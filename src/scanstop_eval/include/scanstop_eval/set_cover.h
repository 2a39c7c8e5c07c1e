#pragma once
/// Greedy set cover with an exact check of pairs: which few candidate scans see most of a set of
/// elements (floor cells, surface elements)? ROS-free, no geometry: elements are ids 0..universe-1.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace scanstop {
namespace eval {

/// The elements one candidate sees: unique ids, in any order.
using ElementSet = std::vector<uint32_t>;

/// The greedy order: each pick the set that adds most uncovered elements (ties: the lower index),
/// until no set adds any.
struct GreedyCover {
  std::vector<size_t> order;    ///< indices into the sets, in the order picked
  std::vector<size_t> covered;  ///< elements covered after picks 1..k (covered[k-1])
};

/// Greedy set cover (lazy evaluation: a set's gain only shrinks as others are picked). Throws
/// std::invalid_argument for an id >= universe.
GreedyCover greedyCover(const std::vector<ElementSet>& sets, size_t universe);

/// The most elements any two sets see together (one set alone when there is only one), found
/// exhaustively on bitsets; std::nullopt when that takes more than max_work word operations
/// (pairs x universe / 64).
std::optional<size_t> bestPairCoverage(const std::vector<ElementSet>& sets, size_t universe, double max_work = 5e8);

/// How many scans reach a share of the total.
struct CoverTarget {
  double share = 0.0;           ///< e.g. 0.99
  std::optional<size_t> scans;  ///< none: no choice of sets reaches it
  bool optimal = false;         ///< no fewer sets can reach it (greedy's 1 or 2, or a pair check)
};

/// The scans needed for each share of `total` elements: the greedy count, and 2 instead when the
/// greedy needs more but some pair reaches the share (best_pair, from bestPairCoverage). The greedy's
/// first pick is the best single set, so 1 and 2 are optimal; 3 is when best_pair is known and short.
std::vector<CoverTarget> scansNeeded(const GreedyCover& greedy, size_t total, const std::vector<double>& shares,
                                     std::optional<size_t> best_pair);

}  // namespace eval
}  // namespace scanstop
