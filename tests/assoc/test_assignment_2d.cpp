// 2-D assignment against brute force on random matrices, square and rectangular, with forbidden entries, and
// infeasible matrices reported without hanging.
#include "assoc/assignment_2d.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

using namespace sextant::assoc;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

// Minimum over every injective map from the shorter side to the longer; +inf when none is feasible.
double brute_force(const Eigen::MatrixXd& c) {
  const bool t = c.rows() > c.cols();
  const Eigen::MatrixXd a = t ? Eigen::MatrixXd(c.transpose()) : c;
  std::vector<int> cols(static_cast<size_t>(a.cols()));
  std::iota(cols.begin(), cols.end(), 0);
  double best = kInf;
  do {
    double s = 0;
    for (int i = 0; i < a.rows(); ++i) s += a(i, cols[static_cast<size_t>(i)]);
    best = std::min(best, s);
  } while (std::next_permutation(cols.begin(), cols.end()));
  return best;
}
}  // namespace

TEST_CASE("2-D assignment equals brute force on random matrices with forbidden entries") {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-5, 10);
  std::bernoulli_distribution forbid(0.3);
  int feasible = 0, infeasible = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 6, m = 1 + (trial / 6) % 6;
    Eigen::MatrixXd c(n, m);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < m; ++j) c(i, j) = forbid(rng) ? kInf : u(rng);
    const double expected = brute_force(c);
    const auto r = solve_assignment_2d(c);
    CAPTURE(c);
    if (std::isinf(expected)) {
      CHECK_FALSE(r.feasible);
      ++infeasible;
      continue;
    }
    ++feasible;
    REQUIRE(r.feasible);
    CHECK(r.cost == doctest::Approx(expected).epsilon(1e-12));
    // A valid assignment: distinct columns, the cost adds up, no forbidden pair.
    std::vector<int> used;
    double s = 0;
    for (int i = 0; i < n; ++i) {
      const int j = r.column_of_row[static_cast<size_t>(i)];
      if (j < 0) continue;
      used.push_back(j);
      s += c(i, j);
    }
    std::sort(used.begin(), used.end());
    CHECK(std::adjacent_find(used.begin(), used.end()) == used.end());
    CHECK(static_cast<int>(used.size()) == std::min(n, m));
    CHECK(s == doctest::Approx(r.cost));
  }
  CHECK(feasible > 100);
  CHECK(infeasible > 10);
}

TEST_CASE("the dual potentials certify optimality") {
  Eigen::MatrixXd c(3, 4);
  c << 4, 1, 3, 9, 2, 0, 5, 7, 3, 2, 2, 1;
  const auto r = solve_assignment_2d(c);
  REQUIRE(r.feasible);
  CHECK(r.cost == 4.0);  // rows 0, 1, 2 to columns 1, 0, 3: 1 + 2 + 1
  CHECK(r.cost == doctest::Approx(brute_force(c)));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 4; ++j) CHECK(r.u[static_cast<size_t>(i)] + r.v[static_cast<size_t>(j)] <= c(i, j) + 1e-12);
}
