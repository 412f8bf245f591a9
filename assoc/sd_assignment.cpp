#include "assoc/sd_assignment.hpp"

#include "assoc/assignment_with_missed.hpp"
#include "assoc/lagrangian_relaxation.hpp"
#include "assoc/packing_branch_and_bound.hpp"
#include "assoc/relaxation_bound.hpp"
#include "assoc/relaxation_problem.hpp"
#include "assoc/tuple_packing.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace sextant::assoc {
namespace {

// Components with at most this many detections are solved exactly by the branch and bound (a few hundred nodes at
// most, less work than one relaxation iteration on a scan), within kSmallComponentNodes nodes (the relaxation
// takes over if they run out).  Why: the relaxation's bound is the packing LP's, and on the smallest components
// the LP is often fractional.  The typical one is three detections, one per sensor, with the three pairs but no
// triple worth more: x = 1/2 on each pair is an LP solution a third better than any assignment.  Such a
// component's bound can never be closed, and its absolute gap pushed the scan's total gap over the tolerance on 5
// of the 6 grid scans in 1000 that ended above 1 %.
constexpr int kSmallComponentDetections = 8;
constexpr long kSmallComponentNodes = 100'000;
// A component whose gap is still above the tolerance after the iteration limit is solved again with another sensor
// relaxed (the sensor order rotated by one, then by two): the recovery then fixes a different pair of sensors from
// the relaxed solution, so it reaches pairings the first run's recovery and local search could not (with the
// target prior, the stalled scans' upper bounds were 0.8-1.7 % above the optimum while the lower bound sat at the
// LP bound).  Only the stalled components pay for it.
constexpr size_t kExtraRotations = 2;
// A component whose gap is still open after the rotations goes to the branch and bound over the tuples that
// reduced-cost fixing leaves at the relaxation's best multipliers (relaxation_bound.hpp), within this many nodes:
// it proves (or finds) the optimum where the LP bound is fractional, which no Lagrangian multiplier can close.
constexpr long kFallbackNodes = 2000;
// solve_sd_exact: relaxation iterations for the incumbent and the multipliers of the branch and bound's bound.
constexpr int kExactIterations = 300;
// ... stopping when its gap is below this (cost units): the branch and bound then proves the rest.  With 0 the
// bounds, which meet only up to rounding, kept it running to the limit on every component.
constexpr double kExactGap = 1e-9;

// Clamped at 0: when the bounds meet, rounding can put the lower one a few ulps above the upper one.
double relative_gap(double ub, double lb) {
  return std::abs(ub) > 1e-12 ? std::max(0.0, (ub - lb) / std::abs(ub)) : 0.0;
}

// The caller's tuples as detection sets (detection (s, k >= 1) has id offset[s] + k - 1).
TuplePacking packing_of(const std::vector<Tuple>& tuples, const std::vector<int>& n) {
  std::vector<int> offset;
  TuplePacking p;
  for (int c : n) offset.push_back(p.detections), p.detections += c;
  p.ids.reserve(tuples.size() * n.size());
  std::vector<int> m;
  for (const auto& t : tuples) {
    if (t.index.size() != n.size())
      throw std::invalid_argument("S-D assignment: a tuple has " + std::to_string(t.index.size()) + " indices for " +
                                  std::to_string(n.size()) + " sensors");
    m.clear();
    for (size_t s = 0; s < n.size(); ++s) {
      if (t.index[s] < 0 || t.index[s] > n[s])
        throw std::invalid_argument("S-D assignment: index " + std::to_string(t.index[s]) + " of sensor " +
                                    std::to_string(s) + " outside 0.." + std::to_string(n[s]));
      if (t.index[s] > 0) m.push_back(offset[s] + t.index[s] - 1);
    }
    p.add(m, t.cost);
  }
  return p;
}

// The sub-problem of one component, with detection ids renumbered 0..d-1.
TuplePacking restrict_to(const TuplePacking& all, const std::vector<int>& group) {
  TuplePacking p;
  std::vector<int> local(static_cast<size_t>(all.detections), -1), m;
  for (int t : group) {
    m.clear();
    for (int d : all.members(static_cast<size_t>(t))) {
      int& l = local[static_cast<size_t>(d)];
      if (l < 0) l = p.detections++;
      m.push_back(l);
    }
    p.add(m, all.cost[static_cast<size_t>(t)]);
  }
  return p;
}

// One component exactly (packing_branch_and_bound.hpp): the incumbent is `start` (or, when empty, the greedy
// cheapest-first packing) improved by exchange moves; the multipliers are the equal shares raised by
// `dual_iterations` subgradient steps on the packing's Lagrangian.  `nodes` counts against the caller's budget.
PackingSolution solve_exactly(const TuplePacking& p, std::vector<int> start, long max_nodes, long& nodes,
                              int dual_iterations) {
  if (start.empty()) {
    std::vector<int> order(p.size());
    for (size_t t = 0; t < p.size(); ++t) order[t] = static_cast<int>(t);
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return p.cost[static_cast<size_t>(a)] < p.cost[static_cast<size_t>(b)]; });
    std::vector<char> used(static_cast<size_t>(p.detections), 0);
    for (int t : order) {
      const auto m = p.members(static_cast<size_t>(t));
      if (p.cost[static_cast<size_t>(t)] >= 0 ||
          std::any_of(m.begin(), m.end(), [&](int d) { return used[static_cast<size_t>(d)]; }))
        continue;
      for (int d : m) used[static_cast<size_t>(d)] = 1;
      start.push_back(t);
    }
  }
  const double ub = improve_by_exchange(p, start, 20);
  std::vector<double> v = equal_share_multipliers(p);
  maximize_packing_lagrangian(p, v, ub, dual_iterations);
  auto sol = solve_packing_exactly(p, start, v, std::max(0L, max_nodes - nodes));
  nodes += sol.nodes;
  return sol;
}

// Two sensors: an exact 2-D assignment (a tuple with one detection is that detection's cost of staying unpaired).
ComponentResult solve_two_sensors(const RelaxationProblem& P) {
  ComponentResult r;
  std::vector<double> row_missed(static_cast<size_t>(P.n[0]), 0.0), column_missed(static_cast<size_t>(P.n[1]), 0.0);
  std::vector<int> row_tuple(row_missed.size(), -1), column_tuple(column_missed.size(), -1), pair_tuple;
  std::vector<PairCost> pairs;
  for (size_t t = 0; t < P.size(); ++t) {
    const int a = P.at(t, 0) - 1, b = P.at(t, 1) - 1;
    if (a >= 0 && b >= 0)
      pairs.push_back({a, b, P.cost[t]}), pair_tuple.push_back(static_cast<int>(t));
    else if (a >= 0 && P.cost[t] < row_missed[static_cast<size_t>(a)])
      row_missed[static_cast<size_t>(a)] = P.cost[t], row_tuple[static_cast<size_t>(a)] = static_cast<int>(t);
    else if (b >= 0 && P.cost[t] < column_missed[static_cast<size_t>(b)])
      column_missed[static_cast<size_t>(b)] = P.cost[t], column_tuple[static_cast<size_t>(b)] = static_cast<int>(t);
  }
  const auto a = assign_with_missed(row_missed, column_missed, pairs);
  std::vector<int> chosen;
  for (size_t i = 0; i < pairs.size(); ++i)
    if (a.column_of_row[static_cast<size_t>(pairs[i].row)] == pairs[i].column) chosen.push_back(pair_tuple[i]);
  for (size_t k = 0; k < row_tuple.size(); ++k)
    if (a.column_of_row[k] < 0 && row_tuple[k] >= 0) chosen.push_back(row_tuple[k]);
  for (size_t k = 0; k < column_tuple.size(); ++k)
    if (a.row_of_column[k] < 0 && column_tuple[k] >= 0) chosen.push_back(column_tuple[k]);
  for (int t : chosen) r.chosen.push_back(P.original[static_cast<size_t>(t)]), r.ub += P.cost[static_cast<size_t>(t)];
  r.lb = r.ub;
  return r;
}

// The branch and bound over the tuples reduced-cost fixing leaves at the relaxation's best multipliers, from its
// best solution, within `max_nodes`.  Updates r.
void close_gap(const RelaxationProblem& P, ComponentResult& r, long max_nodes) {
  std::vector<int> position(P.size());  // group position -> P's tuple
  for (size_t t = 0; t < P.size(); ++t) position[static_cast<size_t>(P.original[t])] = static_cast<int>(t);
  std::vector<int> incumbent;
  for (int c : r.chosen) incumbent.push_back(position[static_cast<size_t>(c)]);
  std::sort(incumbent.begin(), incumbent.end());
  const auto survivors = reduced_cost_survivors(P.pair_groups(), r.dual, r.ub, incumbent);
  const auto sol = solve_on_survivors(P, r.u, survivors, incumbent, max_nodes);
  if (sol.cost < r.ub) {
    r.ub = sol.cost;
    r.chosen.clear();
    for (int t : sol.chosen) r.chosen.push_back(P.original[static_cast<size_t>(t)]);
  }
  r.lb = std::max(r.lb, std::min(sol.lower_bound, r.ub));
  r.proven = sol.proven;
}

// A component of at least two tuples by the relaxation (three or more sensors; again with other sensors relaxed
// while its gap stays above the tolerance, then the branch and bound within `max_nodes` while it is still open),
// the 2-D assignment (two sensors) or the branch and bound (one detection).
ComponentResult solve_component(const std::vector<Tuple>& tuples, const std::vector<int>& group,
                                const std::vector<int>& n, const TuplePacking& all, int max_iterations,
                                double gap_tolerance, long max_nodes) {
  ComponentResult r;
  const RelaxationProblem P(tuples, group, n);
  if (P.sensors() >= 3) {
    r = solve_relaxation(P, max_iterations, gap_tolerance);
    // The branch and bound below fixes tuples at the multipliers of the run (first or rotated) with the best bound:
    // the rotations reach different bounds.  On a 3 x 20 grid scan with false alarms (d = 0.5 km) the first run's
    // was 0.67 below a rotation's: 515 tuples survived instead of 315, and the exact solver ran out of its 200 000
    // nodes where it now proves the optimum in 1343.
    std::optional<RelaxationProblem> rotated;  // that run's problem, when a rotation's
    for (size_t rotation = 1; rotation <= kExtraRotations && rotation < P.sensors() && r.ub - r.lb > gap_tolerance;
         ++rotation) {
      RelaxationProblem Q(tuples, group, n, rotation);
      auto q = solve_relaxation(Q, max_iterations, gap_tolerance);
      r.lb = std::max(r.lb, q.lb);  // both bound the same component from below
      r.iterations += q.iterations;
      if (q.ub < r.ub) r.ub = q.ub, r.chosen = q.chosen;
      if (!q.dual.reduced.empty() && (r.dual.reduced.empty() || q.dual.bound > r.dual.bound)) {
        r.u = std::move(q.u), r.dual = std::move(q.dual);
        rotated.emplace(std::move(Q));
      }
    }
    if (r.ub - r.lb > gap_tolerance && max_nodes > 0 && !r.dual.reduced.empty())
      close_gap(rotated ? *rotated : P, r, max_nodes);
  } else if (P.sensors() == 2) {
    r = solve_two_sensors(P);
    r.proven = true;
  } else {  // one detection, several single-detection tuples
    long nodes = 0;
    const auto sol = solve_exactly(restrict_to(all, group), {}, 1'000'000, nodes, 0);
    r.chosen = sol.chosen, r.ub = sol.cost, r.lb = sol.lower_bound, r.proven = sol.proven;
  }
  if (r.ub - r.lb <= 1e-9 * std::max(1.0, std::abs(r.ub))) r.proven = true;
  return r;
}

void add_component(SdSolution& out, const std::vector<int>& group, const std::vector<int>& chosen_in_group) {
  for (int c : chosen_in_group) out.tuples.push_back(group[static_cast<size_t>(c)]);
  ++out.components;
  out.largest_component = std::max(out.largest_component, static_cast<int>(group.size()));
}

void finish(SdSolution& out) {
  std::sort(out.tuples.begin(), out.tuples.end());
  out.lower_bound = std::min(out.lower_bound, out.cost);
  out.absolute_gap = out.cost - out.lower_bound;
  out.gap = relative_gap(out.cost, out.lower_bound);
}

}  // namespace

SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& n, long max_nodes) {
  const TuplePacking all = packing_of(tuples, n);
  SdSolution out;
  bool proven = true;
  for (const auto& group : independent_components(all)) {
    // The relaxation run to its limit for an incumbent and multipliers, then the branch and bound proves the
    // optimum (or runs out: not proven).
    const auto r = solve_component(tuples, group, n, all, kExactIterations, kExactGap, max_nodes);
    add_component(out, group, r.chosen);
    out.cost += r.ub;
    out.lower_bound += r.lb;
    proven = proven && r.proven;
  }
  out.exact = proven;
  finish(out);
  return out;
}

SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& n, int max_iterations,
                               double gap_tolerance) {
  const TuplePacking all = packing_of(tuples, n);
  SdSolution out;
  for (const auto& group : independent_components(all)) {
    ComponentResult r;
    if (group.size() == 1) {  // one tuple: take it when it beats the false alarms
      if (all.cost[static_cast<size_t>(group[0])] < 0) r.chosen = {0}, r.ub = all.cost[static_cast<size_t>(group[0])];
      r.lb = r.ub;
    } else {
      // A small component is solved exactly first (k detections hold fewer than 2^k distinct tuples).
      bool solved = false;
      if (group.size() < (1u << kSmallComponentDetections)) {
        const TuplePacking sub = restrict_to(all, group);
        if (sub.detections <= kSmallComponentDetections) {
          long nodes = 0;
          const auto sol = solve_exactly(sub, {}, kSmallComponentNodes, nodes, 0);
          r.chosen = sol.chosen, r.ub = sol.cost, r.lb = sol.lower_bound, solved = sol.proven;
        }
      }
      if (!solved) r = solve_component(tuples, group, n, all, max_iterations, gap_tolerance, kFallbackNodes);
    }
    add_component(out, group, r.chosen);
    out.cost += r.ub;
    out.lower_bound += r.lb;
    out.iterations = std::max(out.iterations, r.iterations);
  }
  finish(out);
  out.exact = out.absolute_gap <= 1e-9 * std::max(1.0, std::abs(out.cost));
  return out;
}

}  // namespace sextant::assoc
