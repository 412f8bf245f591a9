// The primal recovery of the S-D Lagrangian relaxation (assoc/relaxation_recovery.hpp) and the sorted tuple ranges
// it looks up (assoc/relaxation_problem.hpp), against independent computations by linear scans over all tuples:
// every prefix's range, also searched within a window; the recovered tuples stage by stage (3 and 4 sensors, random
// multipliers and relaxed pairings).
#include "assoc/relaxation_problem.hpp"
#include "assoc/relaxation_recovery.hpp"

#include "assoc/assignment_with_missed.hpp"
#include "assoc/bearing_model.hpp"
#include "crowded_scan.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

using namespace sextant::assoc;

namespace {

using test::crowded_scan;
using test::sizes;

bool same_prefix(const RelaxationProblem& P, size_t t, const int* prefix, size_t L) {
  for (size_t q = 0; q < L; ++q)
    if (P.at(t, q) != prefix[q]) return false;
  return true;
}

// The recovery as its header states it, by linear scans: the relaxed pairs fixed, then each sensor q = 3..S added by
// a 2-D assignment of the partial tuples against q's detections, extending by k costing the least
// c_t - sum over later sensors of u of the tuples with that prefix and k; 0 (or the least such tuple missing q, when
// negative) for leaving it; unassigned detections start partial tuples of their own.
std::vector<int> reference_recovery(const RelaxationProblem& P, const Multipliers& u, const MissedAssignment& relaxed) {
  const size_t S = P.sensors();
  std::vector<std::vector<int>> partial;
  for (int a = 0; a < P.n[0]; ++a) {
    std::vector<int> p(S, 0);
    p[0] = a + 1, p[1] = relaxed.column_of_row[static_cast<size_t>(a)] + 1;
    partial.push_back(p);
  }
  for (int b = 0; b < P.n[1]; ++b)
    if (relaxed.row_of_column[static_cast<size_t>(b)] < 0) {
      std::vector<int> p(S, 0);
      p[1] = b + 1;
      partial.push_back(p);
    }
  for (size_t s = 2; s < S; ++s) {
    const size_t rows = partial.size();
    std::vector<double> row_missed(rows, 0.0), column_missed(static_cast<size_t>(P.n[s]), 0.0);
    std::vector<PairCost> pairs;
    for (size_t p = 0; p < rows; ++p) {
      std::vector<double> best(static_cast<size_t>(P.n[s]) + 1, std::numeric_limits<double>::infinity());
      for (size_t t = 0; t < P.size(); ++t) {
        if (!same_prefix(P, t, partial[p].data(), s)) continue;
        double r = P.cost[t];
        for (size_t q = s + 1; q < S; ++q) r -= u[q][static_cast<size_t>(P.at(t, q))];
        auto& b = best[static_cast<size_t>(P.at(t, s))];
        b = std::min(b, r);
      }
      row_missed[p] = std::min(0.0, best[0]);
      for (int k = 1; k <= P.n[s]; ++k)
        if (best[static_cast<size_t>(k)] < std::numeric_limits<double>::infinity())
          pairs.push_back({static_cast<int>(p), k - 1, best[static_cast<size_t>(k)]});
    }
    const auto a = assign_with_missed(row_missed, column_missed, pairs);
    for (size_t p = 0; p < rows; ++p) partial[p][s] = a.column_of_row[p] + 1;
    for (int k = 0; k < P.n[s]; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0) {
        std::vector<int> p(S, 0);
        p[s] = k + 1;
        partial.push_back(p);
      }
  }
  std::vector<int> chosen;
  for (const auto& p : partial)
    for (size_t t = 0; t < P.size(); ++t)
      if (same_prefix(P, t, p.data(), S)) chosen.push_back(static_cast<int>(t));
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace

TEST_CASE("tuple ranges by prefix, whole and within a window, equal a linear scan") {
  std::mt19937 rng(5);
  int prefixes = 0;
  for (size_t sensors : {3u, 4u}) {
    const Scan scan = crowded_scan(rng, sensors, 10, 0.9, 2.0);
    const auto tuples = build_tuples(scan, CostOptions{});
    REQUIRE(tuples.size() > 50);
    std::vector<int> group(tuples.size());
    std::iota(group.begin(), group.end(), 0);
    const RelaxationProblem P(tuples, group, sizes(scan));
    REQUIRE(P.sensors() == sensors);
    for (size_t t = 0; t < P.size(); ++t)
      for (size_t L = 1; L <= P.sensors(); ++L) {
        const int* prefix = P.index.data() + t * P.sensors();
        int lo = -1, hi = -1;
        for (size_t x = 0; x < P.size(); ++x)
          if (same_prefix(P, x, prefix, L)) {
            if (lo < 0) lo = static_cast<int>(x);
            hi = static_cast<int>(x) + 1;
          }
        for (size_t x = static_cast<size_t>(lo); x < static_cast<size_t>(hi); ++x)
          REQUIRE(same_prefix(P, x, prefix, L));
        CHECK(P.range(prefix, L) == std::pair<int, int>(lo, hi));
        const auto window = P.range(prefix, 1);  // the tuples sharing the first index hold the whole range
        CHECK(P.range(prefix, L, window.first, window.second) == std::pair<int, int>(lo, hi));
        ++prefixes;
      }
    // A prefix no tuple has: an empty range.
    const std::vector<int> absent(sensors, P.n[0] + 1);
    const auto none = P.range(absent.data(), sensors);
    CHECK(none.first == none.second);
  }
  CHECK(prefixes > 500);
}

TEST_CASE("the recovery equals a stage-by-stage reference by linear scans, with 3 and 4 sensors") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int checked = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const size_t sensors = trial % 2 ? 4 : 3;
    const Scan scan = crowded_scan(rng, sensors, 6 + trial % 6, 0.9, 1.5);
    const auto tuples = build_tuples(scan, CostOptions{});
    std::vector<int> group(tuples.size());
    std::iota(group.begin(), group.end(), 0);
    const RelaxationProblem P(tuples, group, sizes(scan));
    if (P.sensors() != sensors) continue;
    // Random multipliers on the relaxed sensors and a random partial pairing of sensors 1 and 2.
    Multipliers u = P.zero_multipliers();
    for (size_t q = 2; q < P.sensors(); ++q)
      for (size_t k = 1; k < u[q].size(); ++k) u[q][k] = unit(rng) < 0.2 ? 0.0 : -20 * unit(rng);
    MissedAssignment relaxed;
    relaxed.column_of_row.assign(static_cast<size_t>(P.n[0]), -1);
    relaxed.row_of_column.assign(static_cast<size_t>(P.n[1]), -1);
    std::vector<int> columns(static_cast<size_t>(P.n[1]));
    std::iota(columns.begin(), columns.end(), 0);
    std::shuffle(columns.begin(), columns.end(), rng);
    for (int a = 0; a < P.n[0] && a < P.n[1]; ++a)
      if (unit(rng) < 0.75) {
        relaxed.column_of_row[static_cast<size_t>(a)] = columns[static_cast<size_t>(a)];
        relaxed.row_of_column[static_cast<size_t>(columns[static_cast<size_t>(a)])] = a;
      }
    RelaxationRecovery recovery(P);
    std::vector<int> chosen;
    recovery.recover(u, relaxed, chosen);
    const auto expected = reference_recovery(P, u, relaxed);
    CHECK(chosen == expected);
    // Feasible: no detection in two recovered tuples.
    std::vector<int> uses(static_cast<size_t>(P.packing.detections), 0);
    for (int t : chosen)
      for (int d : P.packing.members(static_cast<size_t>(t))) ++uses[static_cast<size_t>(d)];
    CHECK(std::all_of(uses.begin(), uses.end(), [](int x) { return x <= 1; }));
    // Reused (its buffers kept): another pairing (none: every detection of sensors 1 and 2 on its own), then the
    // first again.
    MissedAssignment unpaired;
    unpaired.column_of_row.assign(static_cast<size_t>(P.n[0]), -1);
    unpaired.row_of_column.assign(static_cast<size_t>(P.n[1]), -1);
    std::vector<int> other, again;
    recovery.recover(u, unpaired, other);
    CHECK(other == reference_recovery(P, u, unpaired));
    recovery.recover(u, relaxed, again);
    CHECK(again == chosen);
    ++checked;
  }
  CHECK(checked >= 20);
}
