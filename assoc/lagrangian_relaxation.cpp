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

// One run of the relaxation: its state across iterations, and the steps of one iteration.
class RelaxationRun {
 public:
  RelaxationRun(const RelaxationProblem& P, double gap_tolerance)
      : P_(P),
        S_(P.sensors()),
        n1_(P.n[0]),
        n2_(P.n[1]),
        gap_tolerance_(gap_tolerance),
        groups_(P.pair_groups()),
        u_(P.zero_multipliers()),
        g_(u_),
        direction_(u_),
        recovery_(P) {
    equal_share_multipliers(P, u_);
  }

  /// One iteration; false when the run is over (gap closed, optimum proven, or a zero subgradient).
  bool iterate(int it) {
    out_.iterations = it + 1;
    P_.reduced_costs(u_, reduced_);
    const auto& a = solve_relaxed_problem();
    const double lb = lower_bound(a);
    record_lower_bound(lb, a);
    collect_relaxed_tuples(a);
    const double g2 = subgradient();
    improve_upper_bound(a);
    take_relaxed_solution();
    if (best_ub_ - best_lb_ <= gap_tolerance_ || g2 == 0) return false;
    if (fix_reduced_costs(it)) return false;
    step_multipliers(lb, g2);
    return true;
  }

  /// The result after the last iteration: gap still open, a last, more thorough exchange pass over the best solution
  /// (more refill candidates, more sweeps).
  ComponentResult finish() {
    if (best_ub_ - best_lb_ > gap_tolerance_) {
      ExchangeImprover thorough(P_.packing, 64);
      std::vector<int> polished = best_;
      const double c = thorough.improve(polished, 20);
      if (c < best_ub_) best_ub_ = c, best_ = polished;
    }
    out_.ub = best_ub_;
    out_.lb = std::min(best_lb_, best_ub_);
    for (int t : best_) out_.chosen.push_back(P_.original[static_cast<size_t>(t)]);
    return std::move(out_);
  }

 private:
  // The relaxed 2-D problem: per (sensor 1, sensor 2) group its cheapest reduced cost, solved with missed rows and
  // columns; tuples missing both sensors take every negative reduced cost (the dummy pair).
  const MissedAssignment& solve_relaxed_problem() {
    row_missed_.assign(static_cast<size_t>(n1_), 0.0), column_missed_.assign(static_cast<size_t>(n2_), 0.0);
    row_tuple_.assign(static_cast<size_t>(n1_), -1), column_tuple_.assign(static_cast<size_t>(n2_), -1);
    pairs_.clear(), pair_tuple_.clear(), relaxed_.clear();
    dummy_pair_ = 0;  // the (0, 0) entry: every negative reduced cost may be taken
    for (const auto& gr : groups_) {
      int arg = gr.lo;
      for (int t = gr.lo; t < gr.hi; ++t) {
        if (reduced_[static_cast<size_t>(t)] < reduced_[static_cast<size_t>(arg)]) arg = t;
        if (gr.a == 0 && gr.b == 0 && reduced_[static_cast<size_t>(t)] < 0)
          dummy_pair_ += reduced_[static_cast<size_t>(t)], relaxed_.push_back(t);
      }
      const double r = reduced_[static_cast<size_t>(arg)];
      if (gr.a == 0 && gr.b == 0) continue;
      if (gr.b == 0) {
        if (r < row_missed_[static_cast<size_t>(gr.a - 1)])
          row_missed_[static_cast<size_t>(gr.a - 1)] = r, row_tuple_[static_cast<size_t>(gr.a - 1)] = arg;
      } else if (gr.a == 0) {
        if (r < column_missed_[static_cast<size_t>(gr.b - 1)])
          column_missed_[static_cast<size_t>(gr.b - 1)] = r, column_tuple_[static_cast<size_t>(gr.b - 1)] = arg;
      } else {
        pairs_.push_back({gr.a - 1, gr.b - 1, r});
        pair_tuple_.push_back(arg);
      }
    }
    return relaxed_solver_.solve(row_missed_, column_missed_, pairs_);
  }

  // L(u): the relaxed problem's value plus each relaxed detection's u, or 0 when its singleton (reduced cost -u) is
  // taken.
  double lower_bound(const MissedAssignment& a) const {
    double lb = a.value + dummy_pair_;
    for (size_t s = 2; s < S_; ++s)
      for (int k = 1; k <= P_.n[s]; ++k) lb += std::min(0.0, u_[s][static_cast<size_t>(k)]);
    return lb;
  }

  // The step factor is halved after kStallLimit iterations without a better bound; a better one is kept with its
  // multipliers and dual solution (for reduced-cost fixing).
  void record_lower_bound(double lb, const MissedAssignment& a) {
    if (lb > best_lb_)
      stalled_ = 0;
    else if (++stalled_ >= kStallLimit)
      factor_ *= 0.5, stalled_ = 0;
    if (lb > best_lb_) {
      out_.u = u_;
      out_.dual.reduced = reduced_, out_.dual.row_dual = a.row_dual, out_.dual.column_dual = a.column_dual,
      out_.dual.bound = lb;
      best_lb_ = lb;
      fixing_due_ = true;
    }
  }

  // The relaxed solution's tuples (after the dummy pair's, already in relaxed_).
  void collect_relaxed_tuples(const MissedAssignment& a) {
    pair_of_row_.assign(static_cast<size_t>(n1_), -1);
    for (size_t i = 0; i < pairs_.size(); ++i)
      if (a.column_of_row[static_cast<size_t>(pairs_[i].row)] == pairs_[i].column)
        pair_of_row_[static_cast<size_t>(pairs_[i].row)] = pair_tuple_[i];
    for (int r = 0; r < n1_; ++r) {
      if (a.column_of_row[static_cast<size_t>(r)] >= 0)
        relaxed_.push_back(pair_of_row_[static_cast<size_t>(r)]);
      else if (row_tuple_[static_cast<size_t>(r)] >= 0)
        relaxed_.push_back(row_tuple_[static_cast<size_t>(r)]);
    }
    for (int k = 0; k < n2_; ++k)
      if (a.row_of_column[static_cast<size_t>(k)] < 0 && column_tuple_[static_cast<size_t>(k)] >= 0)
        relaxed_.push_back(column_tuple_[static_cast<size_t>(k)]);
  }

  // Subgradient of the relaxed constraints, g = 1 - uses (the singleton counts as a use); returns |g|^2 and notes
  // whether the relaxed solution uses no detection twice.
  double subgradient() {
    double g2 = 0;
    relaxed_feasible_ = true;
    for (size_t s = 2; s < S_; ++s) {
      for (int k = 1; k <= P_.n[s]; ++k) g_[s][static_cast<size_t>(k)] = u_[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0;
      for (int t : relaxed_) {
        const int k = P_.at(static_cast<size_t>(t), s);
        if (k > 0) g_[s][static_cast<size_t>(k)] -= 1;
      }
      for (int k = 1; k <= P_.n[s]; ++k) {
        g2 += g_[s][static_cast<size_t>(k)] * g_[s][static_cast<size_t>(k)];
        relaxed_feasible_ =
            relaxed_feasible_ && (u_[s][static_cast<size_t>(k)] > 0 ? 0.0 : 1.0) - g_[s][static_cast<size_t>(k)] <= 1;
      }
    }
    return g2;
  }

  // Upper bound: recovery, then local search.  With three sensors the recovery depends on the relaxed pairing
  // alone (relaxation_recovery.hpp): a pairing seen before gives a recovery seen before, so it is skipped (about
  // 40 % of the recovery's work on the 3 x 20 grid).
  void improve_upper_bound(const MissedAssignment& a) {
    if (S_ == 3) {
      if (std::find(pairings_.begin(), pairings_.end(), a.column_of_row) != pairings_.end()) return;
      pairings_.push_back(a.column_of_row);
    }
    recovery_.recover(u_, a, feasible_);
    double ub = 0;
    for (int t : feasible_) ub += P_.cost[static_cast<size_t>(t)];
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
    const bool promising = ub <= best_recovery_;
    best_recovery_ = std::min(best_recovery_, ub);
    if (promising && std::find(recovered_.begin(), recovered_.end(), feasible_) == recovered_.end()) {
      recovered_.push_back(feasible_);
      if (!reassignment_) reassignment_.emplace(S_, P_.n, P_.index, P_.cost);
      ub = reassignment_->improve(feasible_);
    }
    if (ub < best_ub_) best_ub_ = ub, best_ = feasible_, fixing_due_ = true;
  }

  // The relaxed solution itself, when it uses no detection twice, is a feasible one; with g = 0 it is optimal (its
  // cost equals the bound), and the run stops.
  void take_relaxed_solution() {
    if (!relaxed_feasible_) return;
    double c = 0;
    for (int t : relaxed_) c += P_.cost[static_cast<size_t>(t)];
    if (c < best_ub_) best_ub_ = c, best_ = relaxed_, std::sort(best_.begin(), best_.end()), fixing_due_ = true;
  }

  // Reduced-cost fixing at the best multipliers (recounted when a bound improved); the branch and bound once few
  // tuples remain (again only when fewer remain than at its last failure).  True when it proved the optimum.
  bool fix_reduced_costs(int it) {
    if (fixing_due_ && it >= kFixingFirstIteration)
      survivors_ = reduced_cost_survivors(groups_, out_.dual, best_ub_, best_), fixing_due_ = false;
    const size_t limit =
        std::min(kFixingTuples, kFixingTuplesStart + kFixingTuplesPerIteration * static_cast<size_t>(it));
    if (survivors_.empty() || survivors_.size() > limit || survivors_.size() >= fixing_failed_) return false;
    const auto sol = solve_on_survivors(P_, out_.u, survivors_, best_, kFixingNodes);
    if (sol.cost < best_ub_) best_ub_ = sol.cost, best_ = sol.chosen;
    if (sol.proven) {
      best_lb_ = best_ub_;
      return true;
    }
    fixing_failed_ = survivors_.size();
    return false;
  }

  // Deflected direction (Camerini, Fratta & Maffioli): only when the new subgradient turns back against the last
  // direction; kept when the two cancel exactly.  Then Polyak's step toward the best upper bound along it.
  void step_multipliers(double lb, double g2) {
    double gd = 0, dd = 0;
    for (size_t s = 2; s < S_; ++s)
      for (int k = 1; k <= P_.n[s]; ++k)
        gd += g_[s][static_cast<size_t>(k)] * direction_[s][static_cast<size_t>(k)],
            dd += direction_[s][static_cast<size_t>(k)] * direction_[s][static_cast<size_t>(k)];
    const double beta = gd < 0 && dd > 0 ? -gd / dd : 0.0;
    double h2 = 0;
    for (size_t s = 2; s < S_; ++s)
      for (int k = 1; k <= P_.n[s]; ++k) {
        const double h = g_[s][static_cast<size_t>(k)] + beta * direction_[s][static_cast<size_t>(k)];
        h2 += h * h;
      }
    const bool deflect = h2 > 1e-12 * g2;
    for (size_t s = 2; s < S_; ++s)
      for (int k = 1; k <= P_.n[s]; ++k)
        direction_[s][static_cast<size_t>(k)] =
            g_[s][static_cast<size_t>(k)] + (deflect ? beta * direction_[s][static_cast<size_t>(k)] : 0.0);
    const double step = factor_ * std::max(best_ub_ - lb, 1e-9 * std::abs(best_ub_)) / (deflect ? h2 : g2);
    for (size_t s = 2; s < S_; ++s)
      for (int k = 1; k <= P_.n[s]; ++k) u_[s][static_cast<size_t>(k)] += step * direction_[s][static_cast<size_t>(k)];
  }

  const RelaxationProblem& P_;
  const size_t S_;
  const int n1_, n2_;
  const double gap_tolerance_;
  const std::vector<RelaxationProblem::PairGroup> groups_;
  ComponentResult out_;
  Multipliers u_, g_, direction_;
  double best_ub_ = 0, best_lb_ = -kInf, factor_ = 1;
  int stalled_ = 0;
  std::vector<int> best_;                           // empty: every detection a false alarm, cost 0
  std::optional<SensorReassignment> reassignment_;  // built at the first promising recovery
  RelaxationRecovery recovery_;
  MissedAssignmentSolver relaxed_solver_;
  std::vector<std::vector<int>> recovered_;  // recoveries already improved (the same one recurs across iterations)
  std::vector<std::vector<int>> pairings_;   // relaxed pairings already recovered (three sensors only, see above)
  std::vector<double> reduced_, row_missed_, column_missed_;
  std::vector<PairCost> pairs_;
  std::vector<int> pair_tuple_, row_tuple_, column_tuple_, relaxed_, pair_of_row_, feasible_, survivors_;
  double dummy_pair_ = 0;
  bool relaxed_feasible_ = true;              // no relaxed detection used twice
  double best_recovery_ = 0;                  // the best recovery's cost before local search
  bool fixing_due_ = false;                   // a bound improved since the tuples were last counted
  size_t fixing_failed_ = kFixingTuples + 1;  // survivors when the branch and bound last ran out of nodes
};

}  // namespace

ComponentResult solve_relaxation(const RelaxationProblem& P, int max_iterations, double gap_tolerance) {
  RelaxationRun run(P, gap_tolerance);
  for (int it = 0; it < max_iterations; ++it)
    if (!run.iterate(it)) break;
  return run.finish();
}

}  // namespace sextant::assoc
