#include "assoc/relaxation_recovery.hpp"

#include <algorithm>
#include <limits>

namespace sextant::assoc {

RelaxationRecovery::RelaxationRecovery(const RelaxationProblem& P) : P_(P) {
  if (P.sensors() < 2) return;
  pair_range_.assign(static_cast<size_t>(P.n[0] + 1) * static_cast<size_t>(P.n[1] + 1), {0, 0});
  for (const auto& g : P.pair_groups())
    pair_range_[static_cast<size_t>(g.a) * static_cast<size_t>(P.n[1] + 1) + static_cast<size_t>(g.b)] = {g.lo, g.hi};
}

std::pair<int, int> RelaxationRecovery::range(const int* prefix, size_t L) const {
  if (pair_range_.empty()) return P_.range(prefix, L);
  const auto window =
      pair_range_[static_cast<size_t>(prefix[0]) * static_cast<size_t>(P_.n[1] + 1) + static_cast<size_t>(prefix[1])];
  if (L == 2 || window.first == window.second) return window;
  return P_.range(prefix, L, window.first, window.second);
}

void RelaxationRecovery::recover(const Multipliers& u, const MissedAssignment& relaxed, std::vector<int>& chosen) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const size_t S = P_.sensors();
  partial_.clear();
  auto start = [&](size_t s, int k) {
    partial_.resize(partial_.size() + S, 0);
    partial_[partial_.size() - S + s] = k;
  };
  for (int a = 0; a < P_.n[0]; ++a)
    start(0, a + 1), partial_[partial_.size() - S + 1] = relaxed.column_of_row[static_cast<size_t>(a)] + 1;
  for (int b = 0; b < P_.n[1]; ++b)
    if (relaxed.row_of_column[static_cast<size_t>(b)] < 0) start(1, b + 1);
  for (size_t s = 2; s < S; ++s) {
    const size_t rows = partial_.size() / S;
    pairs_.clear();
    row_missed_.assign(rows, 0.0);
    for (size_t p = 0; p < rows; ++p) {
      const auto [lo, hi] = range(partial_.data() + p * S, s);
      for (int t = lo; t < hi;) {  // tuples of the range grouped by their index at sensor s (sorted)
        const int k = P_.at(static_cast<size_t>(t), s);
        double best = kInf;
        for (; t < hi && P_.at(static_cast<size_t>(t), s) == k; ++t) {
          double r = P_.cost[static_cast<size_t>(t)];
          for (size_t q = s + 1; q < S; ++q) r -= u[q][static_cast<size_t>(P_.at(static_cast<size_t>(t), q))];
          best = std::min(best, r);
        }
        if (k == 0)
          row_missed_[p] = std::min(0.0, best);
        else
          pairs_.push_back({static_cast<int>(p), k - 1, best});
      }
    }
    column_missed_.assign(static_cast<size_t>(P_.n[s]), 0.0);
    const auto& a = solver_.solve(row_missed_, column_missed_, pairs_);
    for (size_t p = 0; p < rows; ++p) partial_[p * S + s] = a.column_of_row[p] + 1;
    for (int k = 0; k < P_.n[s]; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0) start(s, k + 1);
  }
  chosen.clear();
  for (size_t p = 0; p < partial_.size() / S; ++p) {
    const auto [lo, hi] = range(partial_.data() + p * S, S);
    if (hi > lo) chosen.push_back(lo);
  }
  std::sort(chosen.begin(), chosen.end());
}

}  // namespace sextant::assoc
