// 2-D assignment against brute force on random matrices, square and rectangular, with forbidden entries, and
// infeasible matrices reported without hanging; the assignment with unpaired rows and columns against brute force,
// and its LP dual (feasible, summing to the optimum).
#include "assoc/assignment_2d.hpp"
#include "assoc/assignment_with_missed.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

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

namespace {
// Every partial matching of rows to columns (each row: unpaired or one allowed, unused column).
double brute_force_missed(const std::vector<double>& rm, const std::vector<double>& cm, const Eigen::MatrixXd& c,
                          size_t row, std::vector<bool>& used) {
  if (row == rm.size()) {
    double s = 0;
    for (size_t k = 0; k < cm.size(); ++k) s += used[k] ? 0.0 : cm[k];
    return s;
  }
  double best = rm[row] + brute_force_missed(rm, cm, c, row + 1, used);
  for (size_t k = 0; k < cm.size(); ++k) {
    if (used[k] || !std::isfinite(c(static_cast<Eigen::Index>(row), static_cast<Eigen::Index>(k)))) continue;
    used[k] = true;
    best = std::min(best, c(static_cast<Eigen::Index>(row), static_cast<Eigen::Index>(k)) +
                              brute_force_missed(rm, cm, c, row + 1, used));
    used[k] = false;
  }
  return best;
}
}  // namespace

TEST_CASE(
    "assignment with unpaired rows and columns equals brute force on sparse random instances, also with a reused "
    "solver") {
  std::mt19937 rng(21);
  MissedAssignmentSolver reused;  // one instance over all trials (sizes change from trial to trial)
  std::uniform_real_distribution<double> u(-6, 3);
  std::bernoulli_distribution allowed(0.35);
  for (int trial = 0; trial < 300; ++trial) {
    const int R = 1 + trial % 7, C = 1 + (trial / 7) % 7;
    std::vector<double> rm(static_cast<size_t>(R)), cm(static_cast<size_t>(C));
    for (auto& x : rm) x = trial % 3 == 0 ? 0.0 : u(rng);
    for (auto& x : cm) x = trial % 3 == 0 ? 0.0 : u(rng);
    Eigen::MatrixXd c = Eigen::MatrixXd::Constant(R, C, kInf);
    std::vector<PairCost> pairs;
    for (int r = 0; r < R; ++r)
      for (int k = 0; k < C; ++k)
        if (allowed(rng)) c(r, k) = u(rng) - 3, pairs.push_back({r, k, c(r, k)});
    if (!pairs.empty())
      pairs.push_back({pairs[0].row, pairs[0].column, pairs[0].cost + 1});  // a worse duplicate is ignored
    std::vector<bool> used(static_cast<size_t>(C), false);
    const double expected = brute_force_missed(rm, cm, c, 0, used);
    const auto a = assign_with_missed(rm, cm, pairs);
    CAPTURE(trial);
    CHECK(a.value == doctest::Approx(expected).epsilon(1e-12));
    const auto& again = reused.solve(rm, cm, pairs);
    CHECK(again.value == a.value);
    CHECK(again.column_of_row == a.column_of_row);
    CHECK(again.row_of_column == a.row_of_column);
    // Consistent both ways, only allowed pairs, and the value adds up.
    double s = 0;
    for (int r = 0; r < R; ++r) {
      const int k = a.column_of_row[static_cast<size_t>(r)];
      if (k < 0) {
        s += rm[static_cast<size_t>(r)];
        continue;
      }
      CHECK(a.row_of_column[static_cast<size_t>(k)] == r);
      CHECK(std::isfinite(c(r, k)));
      s += c(r, k);
    }
    for (int k = 0; k < C; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0) s += cm[static_cast<size_t>(k)];
    CHECK(s == doctest::Approx(a.value).epsilon(1e-12));
  }
}

TEST_CASE("assignment with unpaired rows and columns rejects bad input") {
  CHECK_THROWS_AS(assign_with_missed({0.0}, {0.0}, {{1, 0, -1.0}}), std::invalid_argument);
  CHECK_THROWS_AS(assign_with_missed({0.0}, {0.0}, {{0, 0, kInf}}), std::invalid_argument);
  CHECK_THROWS_AS(assign_with_missed({kInf}, {0.0}, {}), std::invalid_argument);
  const auto empty = assign_with_missed({}, {}, {});
  CHECK(empty.value == 0.0);
}

TEST_CASE("assignment with unpaired rows and columns equals the dense 2-D assignment on larger sparse instances") {
  // The same problem stated densely for solve_assignment_2d: rows x (columns, then one zero-cost "unpaired" slot
  // per row), costs as gains over leaving both unpaired.  Up to 60 x 60 with a few pairings per row, as in the
  // relaxation's subproblems.
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-6, 1);
  MissedAssignmentSolver reused;
  for (int trial = 0; trial < 60; ++trial) {
    const int R = 5 + trial % 56, C = 5 + (trial * 7) % 56;
    std::vector<double> rm(static_cast<size_t>(R)), cm(static_cast<size_t>(C));
    for (auto& x : rm) x = u(rng) / 3;
    for (auto& x : cm) x = u(rng) / 3;
    std::vector<PairCost> pairs;
    std::uniform_int_distribution<int> column(0, C - 1), degree(0, 5);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Constant(R, C + R, kInf);
    dense.rightCols(R).setZero();
    double all_unpaired = 0;
    for (double x : rm) all_unpaired += x;
    for (double x : cm) all_unpaired += x;
    for (int r = 0; r < R; ++r)
      for (int n = degree(rng); n > 0; --n) {
        const PairCost p{r, column(rng), u(rng) - 2};
        pairs.push_back(p);
        const double g = p.cost - rm[static_cast<size_t>(r)] - cm[static_cast<size_t>(p.column)];
        if (g < 0) dense(r, p.column) = std::min(dense(r, p.column), g);
      }
    const auto reference = solve_assignment_2d(dense);
    REQUIRE(reference.feasible);
    const auto a = assign_with_missed(rm, cm, pairs);
    CAPTURE(trial);
    CHECK(a.value == doctest::Approx(all_unpaired + reference.cost).epsilon(1e-12));
    CHECK(reused.solve(rm, cm, pairs).value == doctest::Approx(a.value).epsilon(1e-12));
  }
}

TEST_CASE("the unpaired assignment's dual is feasible and sums to its value") {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-6, 3);
  std::bernoulli_distribution allowed(0.35);
  MissedAssignmentSolver solver;
  for (int trial = 0; trial < 300; ++trial) {
    const int R = 1 + trial % 9, C = 1 + (trial / 9) % 9;
    std::vector<double> rm(static_cast<size_t>(R)), cm(static_cast<size_t>(C));
    for (auto& x : rm) x = trial % 3 == 0 ? 0.0 : std::min(0.0, u(rng));
    for (auto& x : cm) x = trial % 3 == 0 ? 0.0 : std::min(0.0, u(rng));
    std::vector<PairCost> pairs;
    for (int r = 0; r < R; ++r)
      for (int k = 0; k < C; ++k)
        if (allowed(rng)) pairs.push_back({r, k, u(rng) - 3});
    const auto& a = solver.solve(rm, cm, pairs);
    CAPTURE(trial);
    REQUIRE(a.row_dual.size() == rm.size());
    REQUIRE(a.column_dual.size() == cm.size());
    double sum = 0;
    for (int r = 0; r < R; ++r) {
      CHECK(a.row_dual[static_cast<size_t>(r)] <= rm[static_cast<size_t>(r)] + 1e-12);
      sum += a.row_dual[static_cast<size_t>(r)];
    }
    for (int k = 0; k < C; ++k) {
      CHECK(a.column_dual[static_cast<size_t>(k)] <= cm[static_cast<size_t>(k)] + 1e-12);
      sum += a.column_dual[static_cast<size_t>(k)];
    }
    for (const auto& p : pairs)
      CHECK(a.row_dual[static_cast<size_t>(p.row)] + a.column_dual[static_cast<size_t>(p.column)] <= p.cost + 1e-12);
    CHECK(sum == doctest::Approx(a.value).epsilon(1e-12));
  }
}
