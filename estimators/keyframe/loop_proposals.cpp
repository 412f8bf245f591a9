#include "estimators/keyframe/loop_proposals.hpp"

#include "estimators/random/portable_random.hpp"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

namespace sextant {

LoopProposer::LoopProposer(const LoopProposalOptions& o) : options_(o) {
  if (o.n1 < 0) throw std::invalid_argument("loop proposals: n1 must be >= 0, got " + std::to_string(o.n1));
  if (o.n2 < -1)
    throw std::invalid_argument("loop proposals: n2 must be >= 0 (or -1 for 2 n1), got " + std::to_string(o.n2));
  n2_ = o.n2 == -1 ? 2 * o.n1 : o.n2;
}

std::vector<LoopProposal> LoopProposer::propose(int64_t k) const {
  if (k < 0) throw std::invalid_argument("loop proposals: negative keyframe index " + std::to_string(k));
  std::vector<LoopProposal> out;
  const int64_t local = std::min<int64_t>(options_.n1, k);
  for (int64_t i = 1; i <= local; ++i) out.push_back({k, k - i, false});

  const int64_t candidates = k - local;  // keyframes 0 .. candidates-1
  const int64_t m = std::min<int64_t>(n2_, candidates);
  if (m <= 0) return out;
  std::vector<int64_t> chosen;
  chosen.reserve(static_cast<size_t>(m));
  if (m == candidates) {
    for (int64_t j = 0; j < candidates; ++j) chosen.push_back(j);
  } else {
    const auto lo = [](uint64_t v) { return static_cast<uint32_t>(v & 0xffffffffu); };
    const auto hi = [](uint64_t v) { return static_cast<uint32_t>(v >> 32); };
    const uint64_t uk = static_cast<uint64_t>(k);
    std::seed_seq seq{lo(options_.seed), hi(options_.seed), lo(uk), hi(uk)};
    std::mt19937_64 rng(seq);
    // Floyd's sampling: m distinct values of 0 .. candidates-1, each m-subset equally likely.
    for (int64_t j = candidates - m; j < candidates; ++j) {
      const auto t = static_cast<int64_t>(random::uniform_index(rng, static_cast<uint64_t>(j + 1)));
      chosen.push_back(std::find(chosen.begin(), chosen.end(), t) == chosen.end() ? t : j);
    }
    std::sort(chosen.begin(), chosen.end());
  }
  for (int64_t j : chosen) out.push_back({k, j, true});
  return out;
}

}  // namespace sextant
