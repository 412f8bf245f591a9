#include "assoc/lagrangian_relaxation.hpp"

#include "assoc/assignment_with_missed.hpp"
#include "assoc/relaxation_recovery.hpp"
#include "assoc/sensor_reassignment.hpp"
#include "assoc/tuple_packing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace sextant::assoc {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Iterations without a better lower bound before the step factor is halved (10 rather than 5 once the multipliers
// start at the equal shares: LR optimal on 299 instead of 298 of the unit test's 300 instances, same iterations).
constexpr int kStallLimit = 10;

// First multipliers: each detection of a relaxed sensor gets the smallest equal share c_t / m_t of the tuples
// holding it (m_t = the tuple's detections; 0 when every such tuple costs >= 0).  These shares are a feasible
// point of the packing LP's dual (each tuple's shares sum to at most its cost), so the first lower bound is at
// least their sum; on the passive scans it starts the subgradient far closer to the optimum than u = 0 (half
// the iterations on the coplanar grid).
void equal_share_multipliers(const RelaxationProblem& P, Multipliers& u) {
  const size_t S = P.sensors();
  for (size_t t = 0; t < P.size(); ++t) {
    int m = 0;
    for (size_t s = 0; s < S; ++s) m += P.at(t, s) > 0;
    const double share = P.cost[t] / m;
    for (size_t s = 2; s < S; ++s) {
      const int k = P.at(t, s);
      if (k > 0) u[s][static_cast<size_t>(k)] = std::min(u[s][static_cast<size_t>(k)], share);
    }
  }
}

}  // namespace

ComponentResult solve_relaxation(const RelaxationProblem& P, int max_iterations, double gap_tolerance) {
  const size_t S = P.sensors();
  const int n1 = P.n[0], n2 = P.n[1];
  ComponentResult out;
  const auto groups = P.pair_groups();
  Multipliers u = P.zero_multipliers(), g = u, direction = u;
  equal_share_multipliers(P, u);
  double best_ub = 0, best_lb = -kInf, factor = 1;
  int stalled = 0;
  std::vector<int> best;  // empty: every detection a false alarm, cost 0
  std::optional<SensorReassignment> reassignment;  // built at the first promising recovery
  RelaxationRecovery recovery(P);
  MissedAssignmentSolver relaxed_solver;
  std::vector<std::vector<int>> recovered;  // recoveries already improved (the same one recurs across iterations)
  std::vector<std::vector<int>> pairings;   // relaxed pairings already recovered (three sensors only, see below)
  std::vector<double> reduced, row_missed, column_missed;
  std::vector<PairCost> pairs;
  std::vector<int> pair_tuple, row_tuple, column_tuple, relaxed, pair_of_row, feasible, survivors;
  double best_recovery = 0;  // the best recovery's cost before local search
  bool fixing_due = false;  // a bound improved since the tuples were last counted
  size_t fixing_failed = kFixingTuples + 1;  // survivors when the branch and bound last ran out of nodes
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    P.reduced_costs(u, reduced);
    // The relaxed 2-D problem.
    row_missed.assign(static_cast<size_t>(n1), 0.0), column_missed.assign(static_cast<size_t>(n2), 0.0);
    row_tuple.assign(static_cast<size_t>(n1), -1), column_tuple.assign(static_cast<size_t>(n2), -1);
    pairs.clear(), pair_tuple.clear(), relaxed.clear();
    double dummy_pair = 0;  // the (0, 0) entry: every negative reduced cost may be taken
    for (const auto& gr : groups) {
      int arg = gr.lo;
      for (int t = gr.lo; t < gr.hi; ++t) {
        if (reduced[static_cast<size_t>(t)] < reduced[static_cast<size_t>(arg)]) arg = t;
        if (gr.a == 0 && gr.b == 0 && reduced[static_cast<size_t>(t)] < 0) dummy_pair += reduced[static_cast<size_t>(t)], relaxed.push_back(t);
      }
      const double r = reduced[static_cast<size_t>(arg)];
      if (gr.a == 0 && gr.b == 0) continue;
      if (gr.b == 0) {
        if (r < row_missed[static_cast<size_t>(gr.a - 1)]) row_missed[static_cast<size_t>(gr.a - 1)] = r, row_tuple[static_cast<size_t>(gr.a - 1)] = arg;
      } else if (gr.a == 0) {
        if (r < column_missed[static_cast<size_t>(gr.b - 1)]) column_missed[static_cast<size_t>(gr.b - 1)] = r, column_tuple[static_cast<size_t>(gr.b - 1)] = arg;
      } else {
        pairs.push_back({gr.a - 1, gr.b - 1, r});
        pair_tuple.push_back(arg);
      }
    }
    const auto& a = relaxed_solver.solve(row_missed, column_missed, pairs);
    double lb = a.value + dummy_pair;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k) lb += std::min(0.0, u[s][static_cast<size_t>(k)]);  // u, or 0 when the singleton (reduced cost -u) is taken
    if (lb > best_lb) stalled = 0;
    else if (++stalled >= kStallLimit) factor *= 0.5, stalled = 0;
    if (lb > best_lb) {
      out.u = u;
      out.dual.reduced = reduced, out.dual.row_dual = a.row_dual, out.dual.column_dual = a.column_dual, out.dual.bound = lb;
      best_lb = lb;
      fixing_due = true;
    }
    // The relaxed solution's tuples.
    pair_of_row.assign(static_cast<size_t>(n1), -1);
    for (size_t i = 0; i < pairs.size(); ++i)
      if (a.column_of_row[static_cast<size_t>(pairs[i].row)] == pairs[i].column) pair_of_row[static_cast<size_t>(pairs[i].row)] = pair_tuple[i];
    for (int r = 0; r < n1; ++r) {
      if (a.column_of_row[static_cast<size_t>(r)] >= 0) relaxed.push_back(pair_of_row[static_cast<size_t>(r)]);
      else if (row_tuple[static_cast<size_t>(r)] >= 0) relaxed.push_back(row_tuple[static_cast<size_t>(r)]);
    }
    for (int k = 0; k < n2; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0 && column_tuple[static_cast<size_t>(k)] >= 0) relaxed.push_back(column_tuple[static_cast<size_t>(k)]);
    // Subgradient of the relaxed constraints: 1 - uses (the singleton counts as a use).
    double g2 = 0;
    bool relaxed_feasible = true;  // no relaxed detection used twice
    for (size_t s = 2; s < S; ++s) {
      for (int k = 1; k <= P.n[s]; ++k) g[s][static_cast<size_t>(k)] = u[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0;
      for (int t : relaxed) {
        const int k = P.at(static_cast<size_t>(t), s);
        if (k > 0) g[s][static_cast<size_t>(k)] -= 1;
      }
      for (int k = 1; k <= P.n[s]; ++k) {
        g2 += g[s][static_cast<size_t>(k)] * g[s][static_cast<size_t>(k)];
        relaxed_feasible = relaxed_feasible && (u[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0) - g[s][static_cast<size_t>(k)] <= 1;
      }
    }
    // Upper bound: recovery, then local search.  With three sensors the recovery depends on the relaxed pairing
    // alone (relaxation_recovery.hpp): a pairing seen before gives a recovery seen before, so it is skipped (about
    // 40 % of the recovery's work on the 3 x 20 grid).
    bool repeated = false;
    if (S == 3) {
      repeated = std::find(pairings.begin(), pairings.end(), a.column_of_row) != pairings.end();
      if (!repeated) pairings.push_back(a.column_of_row);
    }
    if (!repeated) {
      recovery.recover(u, a, feasible);
      double ub = 0;
      for (int t : feasible) ub += P.cost[static_cast<size_t>(t)];
      // Local search on promising recoveries only (the first, and any that ties or beats every earlier recovery
      // before its own local search), each distinct one once, by re-assigning one sensor at a time
      // (sensor_reassignment.hpp):
      // recoveries differ from the optimum mostly by detections traded among the same tuples, which the
      // re-assignment covers (several tuples at once) at a fraction of the exchange moves' cost.  The exchange
      // moves (tuple_packing.hpp) only polish a solution whose gap stays open at the end: with reduced-cost fixing
      // proving most components, running them on the first recovery too cost time for no scan reaching its
      // optimum that did not otherwise (solver time without them, 60 scans each of bench/assoc/timing_driver.cpp's
      // scenarios: grid 3 x 20 + 5 median 1.17 -> 1.06 ms, mean 1.66 -> 1.36 ms, 60/60 optimal either way; with
      // the target prior 0.85 -> 0.73 ms; uniform 3 x 20 + 5 0.16 -> 0.12 ms).
      // Why against the raw recoveries and not the best solution: the local search takes a raw recovery 5-25 cost
      // units down on the grid scans with false alarms, so no later raw recovery reaches the first one's improved
      // cost and the best upper bound stayed 1-5 units above the optimum for dozens of iterations (while
      // reduced-cost fixing needs a close one).  Seeds 1-3 x 20 scans of bench/assoc/timing_driver.cpp's grid
      // 3 x 20 + 5 (120 with the target prior): 6 % fewer instructions in the solver, seed 2's mean time per scan
      // -28 % (its iterations, e.g. 51 -> 26 on one scan), the same optima.
      const bool promising = ub <= best_recovery;
      best_recovery = std::min(best_recovery, ub);
      if (promising && std::find(recovered.begin(), recovered.end(), feasible) == recovered.end()) {
        recovered.push_back(feasible);
        if (!reassignment) reassignment.emplace(S, P.n, P.index, P.cost);
        ub = reassignment->improve(feasible);
      }
      if (ub < best_ub) best_ub = ub, best = feasible, fixing_due = true;
    }
    // The relaxed solution itself, when it uses no detection twice, is a feasible one; with g = 0 it is optimal
    // (its cost equals the bound), and the loop stops below.
    if (relaxed_feasible) {
      double c = 0;
      for (int t : relaxed) c += P.cost[static_cast<size_t>(t)];
      if (c < best_ub) best_ub = c, best = relaxed, std::sort(best.begin(), best.end()), fixing_due = true;
    }
    if (best_ub - best_lb <= gap_tolerance || g2 == 0) break;
    // Reduced-cost fixing at the best multipliers (recounted when a bound improved); the branch and bound once
    // few tuples remain (again only when fewer remain than at its last failure).
    if (fixing_due && it >= kFixingFirstIteration) survivors = reduced_cost_survivors(groups, out.dual, best_ub, best), fixing_due = false;
    const size_t limit = std::min(kFixingTuples, kFixingTuplesStart + kFixingTuplesPerIteration * static_cast<size_t>(it));
    if (!survivors.empty() && survivors.size() <= limit && survivors.size() < fixing_failed) {
      const auto sol = solve_on_survivors(P, out.u, survivors, best, kFixingNodes);
      if (sol.cost < best_ub) best_ub = sol.cost, best = sol.chosen;
      if (sol.proven) {
        best_lb = best_ub;
        break;
      }
      fixing_failed = survivors.size();
    }
    // Deflected direction (Camerini, Fratta & Maffioli): only when the new subgradient turns back against the last
    // direction; kept when the two cancel exactly.
    double gd = 0, dd = 0;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k)
        gd += g[s][static_cast<size_t>(k)] * direction[s][static_cast<size_t>(k)], dd += direction[s][static_cast<size_t>(k)] * direction[s][static_cast<size_t>(k)];
    const double beta = gd < 0 && dd > 0 ? -gd / dd : 0.0;
    double h2 = 0;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k) {
        const double h = g[s][static_cast<size_t>(k)] + beta * direction[s][static_cast<size_t>(k)];
        h2 += h * h;
      }
    const bool deflect = h2 > 1e-12 * g2;
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k)
        direction[s][static_cast<size_t>(k)] = g[s][static_cast<size_t>(k)] + (deflect ? beta * direction[s][static_cast<size_t>(k)] : 0.0);
    const double step = factor * std::max(best_ub - lb, 1e-9 * std::abs(best_ub)) / (deflect ? h2 : g2);
    for (size_t s = 2; s < S; ++s)
      for (int k = 1; k <= P.n[s]; ++k) u[s][static_cast<size_t>(k)] += step * direction[s][static_cast<size_t>(k)];
  }
  // Gap still open: a last, more thorough exchange pass over the best solution (more refill candidates, more sweeps).
  if (best_ub - best_lb > gap_tolerance) {
    ExchangeImprover thorough(P.packing, 64);
    std::vector<int> polished = best;
    const double c = thorough.improve(polished, 20);
    if (c < best_ub) best_ub = c, best = polished;
  }
  out.ub = best_ub;
  out.lb = std::min(best_lb, best_ub);
  for (int t : best) out.chosen.push_back(P.original[static_cast<size_t>(t)]);
  return out;
}

}  // namespace sextant::assoc
