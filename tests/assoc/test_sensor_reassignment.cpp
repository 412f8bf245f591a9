// Sensor-wise re-assignment (assoc/sensor_reassignment.hpp): on a rotation of one sensor's detections among three
// tuples, which the exchange moves cannot find, and on random tuple lists against brute force over every
// re-assignment of each sensor (the result must be a feasible solution no single-sensor re-assignment improves).
#include "assoc/sensor_reassignment.hpp"

#include "assoc/tuple_packing.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

using namespace sextant::assoc;

namespace {

struct List {
  size_t S = 0;
  std::vector<int> n, index;  // flat, sorted rows
  std::vector<double> cost;
  const int* row(size_t t) const { return index.data() + t * S; }
};

List make_list(size_t S, std::vector<int> n, std::map<std::vector<int>, double> tuples) {  // std::map: sorted rows
  List l{S, std::move(n), {}, {}};
  for (const auto& [idx, c] : tuples) l.index.insert(l.index.end(), idx.begin(), idx.end()), l.cost.push_back(c);
  return l;
}

bool disjoint(const List& l, const std::vector<int>& chosen) {
  std::set<std::pair<size_t, int>> used;
  for (int t : chosen)
    for (size_t s = 0; s < l.S; ++s)
      if (const int k = l.row(static_cast<size_t>(t))[s]; k > 0 && !used.insert({s, k}).second) return false;
  return true;
}

double cost_of(const List& l, const std::vector<int>& chosen) {
  double c = 0;
  for (int t : chosen) c += l.cost[static_cast<size_t>(t)];
  return c;
}

// The cheapest solution reachable by re-assigning sensor s alone, by enumeration: every rest (a chosen tuple
// without its sensor-s index, or a free detection of another sensor) takes a distinct detection of s or none.
double best_single_sensor(const List& l, const std::vector<int>& chosen, size_t s) {
  std::map<std::vector<int>, double> cost_of_row;
  for (size_t t = 0; t < l.cost.size(); ++t) cost_of_row[std::vector<int>(l.row(t), l.row(t) + l.S)] = l.cost[t];
  std::vector<std::vector<int>> rests;
  std::set<std::pair<size_t, int>> covered;
  for (int t : chosen) {
    std::vector<int> r(l.row(static_cast<size_t>(t)), l.row(static_cast<size_t>(t)) + l.S);
    for (size_t q = 0; q < l.S; ++q)
      if (r[q] > 0) covered.insert({q, r[q]});
    r[s] = 0;
    rests.push_back(r);
  }
  for (size_t q = 0; q < l.S; ++q)
    for (int k = 1; k <= l.n[q]; ++k)
      if (q != s && !covered.count({q, k})) {
        std::vector<int> r(l.S, 0);
        r[q] = k;
        rests.push_back(r);
      }
  double best = 0;
  std::vector<char> used(static_cast<size_t>(l.n[s]) + 1, 0);
  auto recurse = [&](auto&& self, size_t i, double c) -> void {
    if (i == rests.size()) {
      best = std::min(best, c);
      return;
    }
    auto r = rests[i];
    const auto alone = cost_of_row.find(r);  // unpaired: its own tuple when listed, else its detections are free
    self(self, i + 1, c + (alone != cost_of_row.end() ? alone->second : 0.0));
    for (int k = 1; k <= l.n[s]; ++k) {
      if (used[static_cast<size_t>(k)]) continue;
      r[s] = k;
      const auto it = cost_of_row.find(r);
      if (it == cost_of_row.end()) continue;
      used[static_cast<size_t>(k)] = 1;
      self(self, i + 1, c + it->second);
      used[static_cast<size_t>(k)] = 0;
    }
  };
  recurse(recurse, 0, 0.0);
  return best;
}

}  // namespace

TEST_CASE("sensor re-assignment finds a rotation of one sensor's detections that exchange moves miss") {
  // Three targets seen by three sensors; the current solution pairs sensor 3's detections one step off.
  const List l =
      make_list(3, {3, 3, 3},
                {{{1, 1, 1}, -5}, {{2, 2, 2}, -5}, {{3, 3, 3}, -5}, {{1, 1, 2}, -6}, {{2, 2, 3}, -6}, {{3, 3, 1}, -6}});
  // Rows in map order: (1,1,1) 0, (1,1,2) 1, (2,2,2) 2, (2,2,3) 3, (3,3,1) 4, (3,3,3) 5.
  const std::vector<int> start = {0, 2, 5};  // cost -15
  TuplePacking p;
  p.detections = 9;
  for (size_t t = 0; t < l.cost.size(); ++t) {
    std::vector<int> m;
    for (size_t s = 0; s < 3; ++s) m.push_back(3 * static_cast<int>(s) + l.row(t)[s] - 1);
    p.add(m, l.cost[t]);
  }
  std::vector<int> by_exchange = start;
  CHECK(improve_by_exchange(p, by_exchange) == doctest::Approx(-15.0));  // every single swap costs +4 first
  SensorReassignment r(l.S, l.n, l.index, l.cost);
  std::vector<int> chosen = start;
  CHECK(r.improve(chosen) == doctest::Approx(-18.0));
  CHECK(chosen == std::vector<int>{1, 3, 4});
  // Optimal: nothing to improve, the same solution back.
  CHECK(r.improve(chosen) == doctest::Approx(-18.0));
  CHECK(chosen == std::vector<int>{1, 3, 4});
}

TEST_CASE("sensor re-assignment ends at a feasible solution that no single-sensor re-assignment improves") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(0, 1);
  int improved = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const size_t S = 3 + static_cast<size_t>(trial % 2);
    std::vector<int> n;
    for (size_t s = 0; s < S; ++s) n.push_back(1 + static_cast<int>(rng() % 3));
    std::map<std::vector<int>, double> tuples;
    for (int k = 0; k < 18; ++k) {
      std::vector<int> idx(S);
      int held = 0;
      for (size_t s = 0; s < S; ++s)
        idx[s] = u(rng) < 0.75 ? 1 + static_cast<int>(rng() % static_cast<unsigned>(n[s])) : 0, held += idx[s] > 0;
      if (held >= 2) tuples[idx] = -0.1 - 5 * u(rng);
    }
    if (tuples.empty()) continue;
    const List l = make_list(S, n, tuples);
    // A random greedy start.
    std::vector<int> order(l.cost.size()), chosen;
    for (size_t t = 0; t < order.size(); ++t) order[t] = static_cast<int>(t);
    std::shuffle(order.begin(), order.end(), rng);
    for (int t : order) {
      chosen.push_back(t);
      if (!disjoint(l, chosen)) chosen.pop_back();
    }
    const double before = cost_of(l, chosen);
    SensorReassignment r(l.S, l.n, l.index, l.cost);
    const double after = r.improve(chosen, 100);
    REQUIRE(disjoint(l, chosen));
    CHECK(after == doctest::Approx(cost_of(l, chosen)));
    CHECK(after <= before + 1e-12);
    improved += after < before - 1e-9;
    for (size_t s = 0; s < S; ++s) CHECK(best_single_sensor(l, chosen, s) >= after - 1e-9);
  }
  MESSAGE("improved " << improved << " of 200 greedy starts");
  CHECK(improved >= 20);  // the test exercises improving moves, not only fixed points
}

TEST_CASE("sensor re-assignment rejects an unsorted tuple list") {
  const std::vector<int> n = {2, 2, 2}, index = {2, 1, 1, 1, 1, 1};
  const std::vector<double> cost = {-1, -1};
  CHECK_THROWS_AS(SensorReassignment(3, n, index, cost), std::invalid_argument);
}
