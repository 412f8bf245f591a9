// Loop proposals of the Kinect visual-odometry paper (Sensors and Microsystems 2019): local and random sets,
// checked against an independent reimplementation of the documented draw, a fixed golden case, and the structural
// rules (no duplicates, never itself or the future, fewer candidates than n2, uniform choice).
#include "estimators/keyframe/loop_proposals.hpp"
#include "estimators/random/portable_random.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <stdexcept>

using namespace sextant;

namespace {

// The documented draw, written independently: the rejection test by blocks, std::set for Floyd.
std::set<int64_t> reference_random_set(uint64_t seed, int64_t k, int n1, int n2) {
  const int64_t M = k - std::min<int64_t>(n1, k);
  const int64_t m = std::min<int64_t>(n2, M);
  std::set<int64_t> S;
  if (m <= 0) return S;
  if (m == M) {
    for (int64_t j = 0; j < M; ++j) S.insert(j);
    return S;
  }
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(k),
                    static_cast<uint32_t>(static_cast<uint64_t>(k) >> 32)};
  std::mt19937_64 rng(seq);
  for (int64_t j = M - m; j < M; ++j) {
    // Accept x when its whole block of n values [x - x mod n, x - x mod n + n - 1] fits below 2^64.
    const auto n = static_cast<uint64_t>(j + 1);
    uint64_t x;
    do x = rng();
    while (x - x % n > UINT64_MAX - (n - 1));
    const auto t = static_cast<int64_t>(x % n);
    S.insert(S.count(t) ? j : t);
  }
  return S;
}

}  // namespace

TEST_CASE("loop proposals: local then random sets equal an independent reimplementation of the documented draw") {
  for (const auto& sizes : {std::pair{3, -1}, std::pair{4, 8}, std::pair{1, 5}, std::pair{0, 3}, std::pair{2, 0}}) {
    const int n1 = sizes.first, n2 = sizes.second;  // plain variables: CAPTURE's lambda takes them (clang 14)
    for (const uint64_t seed : {uint64_t{1}, uint64_t{42}, uint64_t{0xdeadbeefcafe1234}}) {
      const LoopProposer p({n1, n2, seed});
      const int resolved_n2 = n2 < 0 ? 2 * n1 : n2;
      for (int64_t k = 0; k < 150; ++k) {
        CAPTURE(n1);
        CAPTURE(n2);
        CAPTURE(seed);
        CAPTURE(k);
        const auto props = p.propose(k);
        std::vector<int64_t> local;
        std::set<int64_t> random;
        for (const auto& x : props) {
          CHECK(x.from == k);
          if (x.random)
            random.insert(x.to);
          else
            local.push_back(x.to);
        }
        std::vector<int64_t> expected_local;
        for (int64_t i = 1; i <= std::min<int64_t>(n1, k); ++i) expected_local.push_back(k - i);
        CHECK(local == expected_local);
        CHECK(random == reference_random_set(seed, k, n1, resolved_n2));
      }
    }
  }
}

TEST_CASE("loop proposals: a fixed case (golden values of the portable draw)") {
  // n1 = 3, n2 = 6, seed 1, keyframe 20: local 19, 18, 17; random from 0..16.  These numbers must not change
  // between platforms or standard libraries (recorded once from this implementation).
  const LoopProposer p({3, -1, 1});
  const auto props = p.propose(20);
  std::vector<int64_t> to;
  for (const auto& x : props) to.push_back(x.to);
  REQUIRE(props.size() == 9);
  CHECK(std::vector<int64_t>(to.begin(), to.begin() + 3) == std::vector<int64_t>{19, 18, 17});
  CHECK(std::vector<int64_t>(to.begin() + 3, to.end()) == std::vector<int64_t>{0, 1, 3, 5, 6, 12});
}

TEST_CASE("loop proposals: no duplicates, never itself, never a future keyframe, n1 + n2 when there are enough") {
  const LoopProposer p({4, -1, 7});
  CHECK(p.n2() == 8);
  for (int64_t k = 0; k < 400; ++k) {
    const auto props = p.propose(k);
    std::set<int64_t> seen;
    for (const auto& x : props) {
      CHECK(x.to >= 0);
      CHECK(x.to < k);
      CHECK(seen.insert(x.to).second);
      if (x.random)
        CHECK(x.to < k - 4);  // random ones are not in the local set
      else
        CHECK(x.to >= k - 4);
    }
    CHECK(static_cast<int64_t>(props.size()) == std::min<int64_t>(k, 12));
  }
}

TEST_CASE("loop proposals: fewer candidates than n2 proposes all of them, the first keyframe none") {
  const LoopProposer p({3, 6, 5});
  CHECK(p.propose(0).empty());
  const auto two = p.propose(2);  // local 1, 0; no random candidate
  REQUIRE(two.size() == 2);
  CHECK((two[0].to == 1 && !two[0].random && two[1].to == 0 && !two[1].random));
  const auto seven = p.propose(7);  // local 6, 5, 4; random: all of 0..3 (4 < n2 = 6)
  REQUIRE(seven.size() == 7);
  for (int i = 0; i < 4; ++i) CHECK((seven[3 + i].to == i && seven[3 + i].random));
  const auto nine = p.propose(9);  // local 8, 7, 6; random: all 6 of 0..5
  CHECK(nine.size() == 9);
}

TEST_CASE("loop proposals: each earlier non-local keyframe is drawn with probability n2 / (k - n1)") {
  // Keyframe 20 with n1 = 3, n2 = 6 over 2000 seeds: each of the 17 candidates is chosen with p = 6/17.
  const int trials = 2000;
  std::vector<int> hits(17, 0);
  for (int s = 1; s <= trials; ++s)
    for (const auto& x : LoopProposer({3, 6, static_cast<uint64_t>(s)}).propose(20))
      if (x.random) ++hits[static_cast<size_t>(x.to)];
  const double p = 6.0 / 17.0, sd = std::sqrt(trials * p * (1 - p));
  for (int h : hits) CHECK(std::abs(h - trials * p) < 5 * sd);
}

TEST_CASE("loop proposals: a pure function of (seed, keyframe): call order does not matter, seeds differ") {
  const LoopProposer a({3, -1, 11}), b({3, -1, 11}), c({3, -1, 12});
  std::vector<std::vector<int64_t>> forward, backward(100);
  const auto tos = [](const std::vector<LoopProposal>& v) {
    std::vector<int64_t> t;
    for (const auto& x : v) t.push_back(x.to);
    return t;
  };
  for (int64_t k = 0; k < 100; ++k) forward.push_back(tos(a.propose(k)));
  for (int64_t k = 99; k >= 0; --k) backward[static_cast<size_t>(k)] = tos(b.propose(k));
  CHECK(forward == backward);
  int differ = 0;
  for (int64_t k = 0; k < 100; ++k) differ += tos(c.propose(k)) != forward[static_cast<size_t>(k)];
  CHECK(differ > 80);  // keyframes >= 10 have C(k-3, 6) >= 7 possible sets
}

TEST_CASE("loop proposals: bad options and indices are refused") {
  CHECK_THROWS_AS(LoopProposer({-1, -1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(LoopProposer({3, -2, 1}), std::invalid_argument);
  CHECK_THROWS_AS(LoopProposer({3, -1, 1}).propose(-1), std::invalid_argument);
  CHECK(LoopProposer({0, 0, 1}).propose(50).empty());
}

TEST_CASE("portable random: uniform_index stays in range and is uniform, also for n near 2^64") {
  std::mt19937_64 rng(3);
  CHECK_THROWS_AS(random::uniform_index(rng, 0), std::invalid_argument);
  for (int i = 0; i < 100; ++i) CHECK(random::uniform_index(rng, 1) == 0);
  const uint64_t big = (uint64_t{1} << 63) + 12345;  // rejects almost half the engine outputs
  for (int i = 0; i < 1000; ++i) CHECK(random::uniform_index(rng, big) < big);
  std::vector<int> counts(7, 0);
  const int n = 70000;
  for (int i = 0; i < n; ++i) ++counts[random::uniform_index(rng, 7)];
  for (int c : counts) CHECK(std::abs(c - n / 7.0) < 5 * std::sqrt(n / 7.0 * 6.0 / 7.0));
}

TEST_CASE("portable random: standard_normal has mean 0, variance 1 and normal tails") {
  std::mt19937_64 rng(5);
  const int n = 200000;
  double s = 0, s2 = 0;
  int beyond2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = random::standard_normal(rng);
    REQUIRE(std::isfinite(x));
    s += x, s2 += x * x;
    beyond2 += std::abs(x) > 2;
  }
  CHECK(std::abs(s / n) < 5 / std::sqrt(n));
  CHECK(std::abs(s2 / n - 1) < 5 * std::sqrt(2.0 / n));
  const double p2 = 0.0455003;  // P(|x| > 2)
  CHECK(std::abs(beyond2 - n * p2) < 5 * std::sqrt(n * p2 * (1 - p2)));
  const double u = random::uniform01(rng);
  CHECK((u >= 0 && u < 1));
}
