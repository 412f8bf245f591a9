// S-D assignment: the exact branch and bound against exhaustive search over tuple subsets, and the Lagrangian
// relaxation against the exact optimum on random small passive-sensor scans (bounds always bracket it).
#include "assoc/sd_assignment.hpp"

#include "assoc/bearing_model.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace sextant::assoc;

namespace {

Scan random_scan(std::mt19937& rng, int targets, int sensors, double pd, double clutter) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n(0, 0.005);
  Scan scan;
  const Eigen::Vector3d fixed[3] = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}};
  for (int s = 0; s < sensors; ++s)
    scan.sensors.push_back(s < 3 ? fixed[s] : Eigen::Vector3d(30 * u(rng), 30 * u(rng), 0.1 * s));
  std::vector<Eigen::Vector3d> truth;
  for (int t = 0; t < targets; ++t) truth.push_back({10 + 2 * u(rng), 10 + 2 * u(rng), 4 + u(rng)});
  scan.detections.resize(static_cast<size_t>(sensors));
  for (int s = 0; s < sensors; ++s) {
    for (const auto& x : truth) {
      if (u(rng) > pd) continue;
      const auto h = *bearing(scan.sensors[static_cast<size_t>(s)], x);
      scan.detections[static_cast<size_t>(s)].push_back({h[0] + n(rng), h[1] + n(rng), 0.005, 0.005});
    }
    for (int k = 0; k < std::poisson_distribution<int>(clutter)(rng); ++k)
      scan.detections[static_cast<size_t>(s)].push_back({0.6 + 0.3 * u(rng), 0.1 + 0.2 * u(rng), 0.005, 0.005});
    std::shuffle(scan.detections[static_cast<size_t>(s)].begin(), scan.detections[static_cast<size_t>(s)].end(), rng);
  }
  return scan;
}

std::vector<int> sizes(const Scan& s) {
  std::vector<int> n;
  for (const auto& d : s.detections) n.push_back(static_cast<int>(d.size()));
  return n;
}

// Every subset of pairwise disjoint tuples (tiny lists only).
double brute_force(const std::vector<Tuple>& tuples) {
  double best = 0;
  const size_t T = tuples.size();
  for (unsigned long mask = 0; mask < (1ul << T); ++mask) {
    double c = 0;
    bool ok = true;
    for (size_t a = 0; a < T && ok; ++a) {
      if (!(mask >> a & 1)) continue;
      c += tuples[a].cost;
      for (size_t b = a + 1; b < T && ok; ++b) {
        if (!(mask >> b & 1)) continue;
        for (size_t s = 0; s < tuples[a].index.size(); ++s)
          ok = ok && !(tuples[a].index[s] > 0 && tuples[a].index[s] == tuples[b].index[s]);
      }
    }
    if (ok) best = std::min(best, c);
  }
  return best;
}

}  // namespace

TEST_CASE("exact S-D branch and bound equals exhaustive search") {
  std::mt19937 rng(12);
  int checked = 0;
  for (int trial = 0; trial < 60 && checked < 30; ++trial) {
    const Scan scan = random_scan(rng, 2, 3, 0.9, 0.5);
    CostOptions o;
    const auto tuples = build_tuples(scan, o);
    if (tuples.empty() || tuples.size() > 16) continue;
    ++checked;
    const auto exact = solve_sd_exact(tuples, sizes(scan));
    CHECK(exact.exact);
    CHECK(exact.cost == doctest::Approx(brute_force(tuples)));
  }
  CHECK(checked >= 20);
}

TEST_CASE("Lagrangian relaxation brackets the optimum and finds it on small instances") {
  std::mt19937 rng(13);
  int trials = 0, optimal = 0;
  for (int sensors : {3, 4})
    for (int trial = 0; trial < 40; ++trial) {
      const Scan scan = random_scan(rng, 3, sensors, 0.9, 1.0);
      CostOptions o;
      const auto tuples = build_tuples(scan, o);
      if (tuples.empty()) continue;
      const auto exact = solve_sd_exact(tuples, sizes(scan));
      const auto lr = solve_sd_lagrangian(tuples, sizes(scan), 100, 1e-9);
      ++trials;
      CHECK(lr.lower_bound <= exact.cost + 1e-6);
      CHECK(lr.cost >= exact.cost - 1e-6);
      optimal += std::abs(lr.cost - exact.cost) <= 1e-6 * std::max(1.0, std::abs(exact.cost));
    }
  MESSAGE("Lagrangian relaxation optimal on " << optimal << " of " << trials);
  CHECK(trials >= 60);
  CHECK(optimal >= 0.9 * trials);
}
