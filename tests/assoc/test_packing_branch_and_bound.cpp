// Exact set packing: the Lagrangian bound is below the optimum for any multipliers and reaches the LP value's
// neighbourhood by subgradient ascent; the branch and bound equals an independent dynamic program over subsets of
// detections on random packings, and when its node budget runs out it says so (never a non-optimal answer marked
// proven) with a bound that still holds.
#include "assoc/packing_branch_and_bound.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <random>

using namespace sextant::assoc;

namespace {

// Random packing: `detections` ids in 3 "sensors", tuples of 2-3 detections (at most one per sensor), negative costs.
TuplePacking random_packing(std::mt19937& rng, int per_sensor, int tuples) {
  std::uniform_int_distribution<int> pick(0, per_sensor - 1), size(2, 3);
  std::uniform_real_distribution<double> cost(-30, -1);
  TuplePacking p;
  p.detections = 3 * per_sensor;
  for (int t = 0; t < tuples; ++t) {
    std::vector<int> m;
    const int k = size(rng);
    std::vector<int> sensors = {0, 1, 2};
    std::shuffle(sensors.begin(), sensors.end(), rng);
    for (int i = 0; i < k; ++i) m.push_back(sensors[static_cast<size_t>(i)] * per_sensor + pick(rng));
    std::sort(m.begin(), m.end());
    p.add(m, cost(rng));
  }
  return p;
}

// The optimum by dynamic programming over the set of covered detections: best[S] = the least cost of a packing
// within the detections of S, computed through the lowest detection of S (a false alarm, or in one of its tuples).
double dynamic_program(const TuplePacking& p) {
  const int D = p.detections;
  std::vector<std::vector<std::pair<unsigned, double>>> by_lowest(static_cast<size_t>(D));
  for (size_t t = 0; t < p.size(); ++t) {
    unsigned mask = 0;
    for (int d : p.members(t)) mask |= 1u << d;
    by_lowest[static_cast<size_t>(__builtin_ctz(mask))].push_back({mask, p.cost[t]});
  }
  std::vector<double> best(1u << D, 0.0);
  for (unsigned S = 1; S < (1u << D); ++S) {
    const int low = __builtin_ctz(S);
    double b = best[S & (S - 1)];  // the lowest detection a false alarm
    for (const auto& [mask, c] : by_lowest[static_cast<size_t>(low)])
      if ((mask & S) == mask) b = std::min(b, c + best[S & ~mask]);
    best[S] = b;
  }
  return best[(1u << D) - 1];
}

double cost_of(const TuplePacking& p, const std::vector<int>& chosen) {
  double c = 0;
  std::vector<int> used(static_cast<size_t>(p.detections), 0);
  for (int t : chosen) {
    c += p.cost[static_cast<size_t>(t)];
    for (int d : p.members(static_cast<size_t>(t))) ++used[static_cast<size_t>(d)];
  }
  for (int u : used) REQUIRE(u <= 1);
  return c;
}

}  // namespace

TEST_CASE("packing branch and bound equals a dynamic program over subsets, and its bounds hold") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> v_random(-20, 0);
  for (int trial = 0; trial < 40; ++trial) {
    const int per_sensor = 4 + trial % 3;  // 12-18 detections
    const auto p = random_packing(rng, per_sensor, 10 + 3 * trial);
    const double optimum = dynamic_program(p);
    CAPTURE(trial);
    // Any multipliers <= 0 give a lower bound; the equal shares do, and the ascent only raises it.
    std::vector<double> v(static_cast<size_t>(p.detections));
    for (double& x : v) x = v_random(rng);
    CHECK(packing_lagrangian(p, v) <= optimum + 1e-9);
    auto shares = equal_share_multipliers(p);
    const double share_bound = packing_lagrangian(p, shares);
    CHECK(share_bound <= optimum + 1e-9);
    const double raised = maximize_packing_lagrangian(p, shares, optimum, 200);
    CHECK(raised >= share_bound - 1e-9);
    CHECK(raised <= optimum + 1e-9);
    CHECK(packing_lagrangian(p, shares) == doctest::Approx(raised));
    // Exact from nothing and from random multipliers (the multipliers decide the pruning, never the answer).
    for (const auto& mult : {shares, v}) {
      const auto sol = solve_packing_exactly(p, {}, mult, 10'000'000);
      REQUIRE(sol.proven);
      CHECK(sol.cost == doctest::Approx(optimum).epsilon(1e-12));
      CHECK(cost_of(p, sol.chosen) == doctest::Approx(sol.cost).epsilon(1e-12));
      CHECK(sol.lower_bound == sol.cost);
    }
    // A budget of a few nodes: not proven unless it really finished; the answer feasible, the bound below the optimum.
    const auto cut = solve_packing_exactly(p, {}, equal_share_multipliers(p), 3);
    if (cut.proven)
      CHECK(cut.cost == doctest::Approx(optimum).epsilon(1e-12));
    else
      CHECK(cut.nodes > 3);
    CHECK(cut.cost >= optimum - 1e-9);
    CHECK(cut.lower_bound <= optimum + 1e-9);
    CHECK(cost_of(p, cut.chosen) == doctest::Approx(cut.cost).epsilon(1e-12));
  }
}
