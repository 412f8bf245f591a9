// Reduced-cost fixing and the branch and bound over the tuples it leaves (assoc/relaxation_bound.hpp), against
// independent computations: every tuple's forcing bound is below the optimum of the scan with that tuple forced
// (a dynamic program over detection subsets); the branch and bound over the survivors reaches the same optimum as
// the dynamic program and as the branch and bound over all tuples without fixing; the Lagrangian relaxation with
// fixing reaches the proven optimum on larger passive scans.
#include "assoc/lagrangian_relaxation.hpp"
#include "assoc/packing_branch_and_bound.hpp"
#include "assoc/relaxation_bound.hpp"
#include "assoc/relaxation_problem.hpp"
#include "assoc/sd_assignment.hpp"

#include "assoc/bearing_model.hpp"
#include "crowded_scan.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

using namespace sextant::assoc;

namespace {

// Three sensors (crowded_scan.hpp draws the same scans as before it was shared).
Scan crowded_scan(std::mt19937& rng, int targets, double pd, double clutter) {
  return test::crowded_scan(rng, 3, targets, pd, clutter);
}
using test::sizes;

// best[S] = the cheapest packing of P's tuples within the detection set S (bit d = detection d of P.packing).
std::vector<double> subset_optima(const RelaxationProblem& P) {
  const int D = P.packing.detections;
  std::vector<std::vector<std::pair<unsigned, double>>> by_lowest(static_cast<size_t>(D));
  for (size_t t = 0; t < P.size(); ++t) {
    unsigned mask = 0;
    for (int d : P.packing.members(t)) mask |= 1u << d;
    by_lowest[static_cast<size_t>(__builtin_ctz(mask))].push_back({mask, P.cost[t]});
  }
  std::vector<double> best(1u << D, 0.0);
  for (unsigned S = 1; S < (1u << D); ++S) {
    double b = best[S & (S - 1)];
    for (const auto& [mask, c] : by_lowest[static_cast<size_t>(__builtin_ctz(S))])
      if ((mask & S) == mask) b = std::min(b, c + best[S & ~mask]);
    best[S] = b;
  }
  return best;
}

}  // namespace

TEST_CASE("reduced-cost fixing: every tuple's forcing bound is below the optimum with that tuple forced") {
  std::mt19937 rng(41);
  int checked = 0, tuples_checked = 0, dropped = 0;
  for (int trial = 0; trial < 200 && checked < 25; ++trial) {
    const Scan scan = crowded_scan(rng, 5 + trial % 2, 0.9, 1.0);
    const auto n = sizes(scan);
    if (n[0] + n[1] + n[2] > 20 || std::min({n[0], n[1], n[2]}) == 0) continue;
    const auto tuples = build_tuples(scan, CostOptions{});
    if (tuples.size() < 10) continue;
    std::vector<int> all(tuples.size());
    std::iota(all.begin(), all.end(), 0);
    const RelaxationProblem P(tuples, all, n);
    if (P.sensors() != 3) continue;
    const auto best = subset_optima(P);
    const unsigned full = (1u << P.packing.detections) - 1;
    // The relaxation's multipliers after a few iterations (not optimal: the bound must hold at any u).
    const auto r = solve_relaxation(P, 5 + trial % 20, 0.0);
    REQUIRE(!r.dual.reduced.empty());
    CHECK(r.dual.bound <= best[full] + 1e-9);
    const auto groups = P.pair_groups();
    for (const auto& g : groups)
      for (int t = g.lo; t < g.hi; ++t) {
        unsigned mask = 0;
        for (int d : P.packing.members(static_cast<size_t>(t))) mask |= 1u << d;
        const double forced = P.cost[static_cast<size_t>(t)] + best[full & ~mask];
        const double bound = r.dual.bound + forcing_increase(g, r.dual.reduced[static_cast<size_t>(t)], r.dual.row_dual,
                                                             r.dual.column_dual);
        CHECK(bound <= forced + 1e-9);
        ++tuples_checked;
      }
    // Survivors for the optimum as the upper bound: dropped tuples are in no optimal solution, and the branch and
    // bound over the survivors from an empty incumbent finds the optimum.
    const auto survivors = reduced_cost_survivors(groups, r.dual, best[full], {});
    dropped += static_cast<int>(P.size() - survivors.size());
    const auto sol = solve_on_survivors(P, r.u, survivors, {}, 1'000'000);
    REQUIRE(sol.proven);
    CHECK(sol.cost == doctest::Approx(best[full]).epsilon(1e-12));
    ++checked;
  }
  MESSAGE(checked << " scans, " << tuples_checked << " tuples, " << dropped << " dropped at the optimum");
  CHECK(checked >= 20);
  CHECK(dropped > 0);  // the test would pass vacuously if fixing never dropped anything
}

TEST_CASE("the branch and bound over the survivors equals the one over all tuples without fixing, on larger scans") {
  // Scans of up to ~60 detections (no dynamic program): the reference is the packing branch and bound over every
  // tuple with the relaxation's bound at every node and no reduced-cost fixing.
  std::mt19937 rng(43);
  int checked = 0;
  for (int trial = 0; trial < 40 && checked < 15; ++trial) {
    const Scan scan = crowded_scan(rng, 10 + trial % 8, 0.9, 2.0);
    const auto n = sizes(scan);
    if (std::min({n[0], n[1], n[2]}) == 0) continue;
    const auto tuples = build_tuples(scan, CostOptions{});
    std::vector<int> all(tuples.size());
    std::iota(all.begin(), all.end(), 0);
    const RelaxationProblem P(tuples, all, n);
    if (P.sensors() != 3 || P.size() < 30) continue;
    const auto r = solve_relaxation(P, 30, 0.0);
    std::vector<int> incumbent;
    std::vector<int> position(P.size());
    for (size_t t = 0; t < P.size(); ++t) position[static_cast<size_t>(P.original[t])] = static_cast<int>(t);
    for (int c : r.chosen) incumbent.push_back(position[static_cast<size_t>(c)]);
    std::sort(incumbent.begin(), incumbent.end());
    RelaxationBound bound(P, r.u);
    const auto reference = solve_packing_exactly(
        P.packing, incumbent, equal_share_multipliers(P.packing), 2'000'000,
        [&](const std::vector<char>& c, const std::vector<int>& b, std::vector<double>*) { return bound(c, b); });
    REQUIRE(reference.proven);
    const auto survivors = reduced_cost_survivors(P.pair_groups(), r.dual, r.ub, incumbent);
    const auto sol = solve_on_survivors(P, r.u, survivors, incumbent, 2'000'000);
    REQUIRE(sol.proven);
    CAPTURE(trial);
    CHECK(sol.cost == doctest::Approx(reference.cost).epsilon(1e-12));
    CHECK(survivors.size() <= P.size());
    ++checked;
  }
  CHECK(checked >= 10);
}

TEST_CASE("the relaxation with reduced-cost fixing reaches the proven optimum on larger passive scans") {
  std::mt19937 rng(47);
  int checked = 0, optimal = 0;
  for (int trial = 0; trial < 60 && checked < 30; ++trial) {
    const Scan scan = crowded_scan(rng, 8 + trial % 10, 0.9, 2.0);
    const auto n = sizes(scan);
    const auto tuples = build_tuples(scan, CostOptions{});
    if (tuples.size() < 20) continue;
    const auto exact = solve_sd_exact(tuples, n);
    REQUIRE(exact.exact);
    const auto lr = solve_sd_lagrangian(tuples, n);
    CHECK(lr.lower_bound <= exact.cost + 1e-9);
    CHECK(lr.cost >= exact.cost - 1e-9);
    optimal += std::abs(lr.cost - exact.cost) <= 1e-6 * std::max(1.0, std::abs(exact.cost));
    ++checked;
  }
  MESSAGE("optimal on " << optimal << " of " << checked);
  CHECK(checked >= 25);
  CHECK(optimal >= checked - 1);
}
