#include "assoc/relaxation_bound.hpp"

#include "assoc/packing_branch_and_bound.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sextant::assoc {

double forcing_increase(const RelaxationProblem::PairGroup& g, double reduced, const std::vector<double>& row_dual,
                        const std::vector<double>& column_dual) {
  if (g.a == 0 && g.b == 0) return std::max(0.0, reduced);  // taken on its own whenever negative
  double base = 0;
  if (g.a > 0) base += row_dual[static_cast<size_t>(g.a - 1)];
  if (g.b > 0) base += column_dual[static_cast<size_t>(g.b - 1)];
  return std::max(0.0, reduced - base);  // >= 0 up to rounding (dual feasibility)
}

std::vector<int> reduced_cost_survivors(const std::vector<RelaxationProblem::PairGroup>& groups,
                                        const RelaxedDual& dual, double upper, const std::vector<int>& incumbent) {
  std::vector<int> survivors;
  const double room = upper - dual.bound + 1e-9 * std::max(1.0, std::abs(upper));
  for (const auto& g : groups)
    for (int t = g.lo; t < g.hi; ++t)
      if (forcing_increase(g, dual.reduced[static_cast<size_t>(t)], dual.row_dual, dual.column_dual) <= room)
        survivors.push_back(t);
  for (int t : incumbent)
    if (!std::binary_search(survivors.begin(), survivors.end(), t))
      survivors.insert(std::upper_bound(survivors.begin(), survivors.end(), t), t);
  return survivors;
}

RelaxationBound::RelaxationBound(const RelaxationProblem& P, const Multipliers& u, std::vector<int> subset)
    : P_(P), u_(u), subset_(std::move(subset)) {
  if (subset_.empty())
    for (size_t t = 0; t < P.size(); ++t) subset_.push_back(static_cast<int>(t));
  const size_t S = P.sensors(), N = subset_.size();
  reduced_.resize(N);
  for (size_t i = 0; i < N; ++i) {
    const auto t = static_cast<size_t>(subset_[i]);
    double r = P.cost[t];
    for (size_t q = 2; q < S; ++q) r -= u[q][static_cast<size_t>(P.at(t, q))];
    reduced_[i] = r;
  }
  auto at = [&](size_t i, size_t q) { return P.at(static_cast<size_t>(subset_[i]), q); };
  for (size_t i = 0; i < N;) {
    const int a = at(i, 0), b = at(i, 1), lo = static_cast<int>(i);
    while (i < N && at(i, 0) == a && at(i, 1) == b) ++i;
    groups_.push_back({a, b, lo, static_cast<int>(i)});
  }
}

double RelaxationBound::operator()(const std::vector<char>& covered, const std::vector<int>& blocked,
                                   std::vector<double>* increase) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lb = 0;
  for (size_t q = 2; q < P_.sensors(); ++q)
    for (int k = 1; k <= P_.n[q]; ++k)
      if (!covered[static_cast<size_t>(P_.offset[q] + k - 1)]) lb += std::min(0.0, u_[q][static_cast<size_t>(k)]);
  row_missed_.assign(static_cast<size_t>(P_.n[0]), 0.0), column_missed_.assign(static_cast<size_t>(P_.n[1]), 0.0);
  pairs_.clear();
  for (const auto& g : groups_) {
    double best = kInf;
    for (int i = g.lo; i < g.hi; ++i) {
      if (blocked[static_cast<size_t>(i)]) continue;
      const double r = reduced_[static_cast<size_t>(i)];
      if (g.a == 0 && g.b == 0) lb += std::min(0.0, r);
      best = std::min(best, r);
    }
    if (best == kInf || (g.a == 0 && g.b == 0)) continue;
    if (g.b == 0)
      row_missed_[static_cast<size_t>(g.a - 1)] = std::min(row_missed_[static_cast<size_t>(g.a - 1)], best);
    else if (g.a == 0)
      column_missed_[static_cast<size_t>(g.b - 1)] = std::min(column_missed_[static_cast<size_t>(g.b - 1)], best);
    else
      pairs_.push_back({g.a - 1, g.b - 1, best});
  }
  const auto& a = solver_.solve(row_missed_, column_missed_, pairs_);
  if (increase) {
    increase->assign(subset_.size(), 0.0);
    for (const auto& g : groups_)
      for (int i = g.lo; i < g.hi; ++i)
        if (!blocked[static_cast<size_t>(i)])
          (*increase)[static_cast<size_t>(i)] =
              forcing_increase(g, reduced_[static_cast<size_t>(i)], a.row_dual, a.column_dual);
  }
  return lb + a.value;
}

SurvivorSolution solve_on_survivors(const RelaxationProblem& P, const Multipliers& u, const std::vector<int>& survivors,
                                    const std::vector<int>& incumbent, long max_nodes) {
  // The survivors as a packing of their own (detections renumbered), and where each detection is in P.packing.
  TuplePacking sub;
  std::vector<int> detection_of, local(static_cast<size_t>(P.packing.detections), -1), position(P.size(), -1), m;
  for (size_t i = 0; i < survivors.size(); ++i) {
    const auto t = static_cast<size_t>(survivors[i]);
    position[t] = static_cast<int>(i);
    m.clear();
    for (int d : P.packing.members(t)) {
      int& l = local[static_cast<size_t>(d)];
      if (l < 0) l = sub.detections++, detection_of.push_back(d);
      m.push_back(l);
    }
    sub.add(m, P.packing.cost[t]);
  }
  std::vector<int> start;
  for (int t : incumbent) start.push_back(position[static_cast<size_t>(t)]);
  RelaxationBound bound(P, u, survivors);
  std::vector<char> covered(static_cast<size_t>(P.packing.detections), 0);
  auto node_bound = [&](const std::vector<char>& c, const std::vector<int>& blocked, std::vector<double>* increase) {
    for (size_t d = 0; d < c.size(); ++d) covered[static_cast<size_t>(detection_of[d])] = c[d];
    return bound(covered, blocked, increase);
  };
  const auto sol = solve_packing_exactly(sub, start, equal_share_multipliers(sub), max_nodes, node_bound);
  SurvivorSolution out;
  for (int i : sol.chosen) out.chosen.push_back(survivors[static_cast<size_t>(i)]);
  std::sort(out.chosen.begin(), out.chosen.end());
  out.cost = sol.cost, out.lower_bound = sol.lower_bound, out.nodes = sol.nodes, out.proven = sol.proven;
  return out;
}

}  // namespace sextant::assoc
