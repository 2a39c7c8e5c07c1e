#include "scanstop_eval/set_cover.h"

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>
#include <string>
#include <utility>

namespace scanstop {
namespace eval {

namespace {

size_t uncoveredIn(const ElementSet& set, const std::vector<uint8_t>& covered) {
  size_t n = 0;
  for (const uint32_t e : set) n += covered[e] ? 0 : 1;
  return n;
}

/// One bitset of `words` 64-bit words per set.
std::vector<uint64_t> toBitsets(const std::vector<ElementSet>& sets, size_t words) {
  std::vector<uint64_t> bits(sets.size() * words, 0);
  for (size_t i = 0; i < sets.size(); ++i)
    for (const uint32_t e : sets[i]) bits[i * words + e / 64] |= uint64_t{1} << (e % 64);
  return bits;
}

}  // namespace

GreedyCover greedyCover(const std::vector<ElementSet>& sets, size_t universe) {
  for (size_t i = 0; i < sets.size(); ++i)
    for (const uint32_t e : sets[i])
      if (e >= universe)
        throw std::invalid_argument("greedyCover: set " + std::to_string(i) + " holds element " + std::to_string(e) +
                                    " of a universe of " + std::to_string(universe));
  // Max-heap of (gain as last evaluated, -index): the lower index wins a tie.
  using Entry = std::pair<size_t, long long>;
  std::priority_queue<Entry> heap;
  for (size_t i = 0; i < sets.size(); ++i)
    if (!sets[i].empty()) heap.emplace(sets[i].size(), -static_cast<long long>(i));
  std::vector<uint8_t> covered(universe, 0);
  GreedyCover out;
  size_t total = 0;
  while (!heap.empty()) {
    const Entry top = heap.top();
    heap.pop();
    const size_t i = static_cast<size_t>(-top.second);
    const size_t gain = uncoveredIn(sets[i], covered);
    if (gain == 0) continue;
    if (!heap.empty() && Entry(gain, top.second) < heap.top()) {  // stale: another may add more now
      heap.emplace(gain, top.second);
      continue;
    }
    for (const uint32_t e : sets[i]) covered[e] = 1;
    total += gain;
    out.order.push_back(i);
    out.covered.push_back(total);
  }
  return out;
}

std::optional<size_t> bestPairCoverage(const std::vector<ElementSet>& sets, size_t universe, double max_work) {
  if (sets.empty()) return size_t{0};
  const size_t words = (universe + 63) / 64;
  const double n = static_cast<double>(sets.size());
  if (n * (n - 1) / 2 * words > max_work) return std::nullopt;
  std::vector<size_t> by_size(sets.size());
  for (size_t i = 0; i < by_size.size(); ++i) by_size[i] = i;
  std::sort(by_size.begin(), by_size.end(), [&](size_t a, size_t b) { return sets[a].size() > sets[b].size(); });
  const std::vector<uint64_t> bits = toBitsets(sets, words);
  size_t best = sets[by_size[0]].size();
  for (size_t a = 0; a < by_size.size(); ++a) {
    const size_t i = by_size[a];
    if (a + 1 < by_size.size() && sets[i].size() + sets[by_size[a + 1]].size() <= best) break;  // no pair can beat it
    const uint64_t* bi = &bits[i * words];
    for (size_t b = a + 1; b < by_size.size(); ++b) {
      const size_t j = by_size[b];
      if (sets[i].size() + sets[j].size() <= best) break;  // sorted: the rest are smaller still
      const uint64_t* bj = &bits[j * words];
      size_t u = 0;
      for (size_t w = 0; w < words; ++w) u += static_cast<size_t>(__builtin_popcountll(bi[w] | bj[w]));
      best = std::max(best, u);
    }
  }
  return best;
}

std::vector<CoverTarget> scansNeeded(const GreedyCover& greedy, size_t total, const std::vector<double>& shares,
                                     std::optional<size_t> best_pair) {
  std::vector<CoverTarget> out;
  for (const double share : shares) {
    CoverTarget t;
    t.share = share;
    const double need = std::ceil(share * static_cast<double>(total) - 1e-9);
    for (size_t k = 0; k < greedy.covered.size(); ++k)
      if (static_cast<double>(greedy.covered[k]) >= need) {
        t.scans = k + 1;
        break;
      }
    if (t.scans && *t.scans <= 2) {
      t.optimal = true;
    } else if (t.scans && best_pair) {
      if (static_cast<double>(*best_pair) >= need) t.scans = 2;  // a pair the greedy did not find
      t.optimal = *t.scans <= 3;
    }
    out.push_back(t);
  }
  return out;
}

}  // namespace eval
}  // namespace scanstop
