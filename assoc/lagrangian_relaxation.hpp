#pragma once
// The Lagrangian relaxation of one S-D assignment component with three or more sensors (Pattipati, Deb,
// Bar-Shalom & Washburn, IEEE TAC 37(2) 1992; Deb, Yeddanapudi, Pattipati & Bar-Shalom, IEEE TAES 33(2) 1997), on
// the component restated by relaxation_problem.hpp:
//  - the constraints of sensors 3..S are relaxed with multipliers u; the relaxed problem is a 2-D assignment
//    between sensors 1 and 2 whose costs are the tuples' reduced costs minimized over the other indices (tuples
//    missing both take every negative reduced cost); its value L(u) is a lower bound;
//  - upper bounds: the recovery (relaxation_recovery.hpp), improved on promising recoveries (those that tie or
//    beat every earlier recovery, both before local search) by re-assigning one sensor at a time
//    (sensor_reassignment.hpp); the relaxed solution itself counts when it uses no detection twice; exchange moves
//    (tuple_packing.hpp) polish the best solution when the gap stays open at the end;
//  - the multipliers start at each detection's smallest equal share c_t / m_t of the tuples holding it (a feasible
//    point of the packing LP's dual: far fewer iterations than starting at 0);
//  - they follow a deflected subgradient (Camerini, Fratta & Maffioli, Math. Programming Study 3, 1975): the
//    direction d_k = g_k + beta_k d_(k-1), beta_k = -g_k.d_(k-1) / |d_(k-1)|^2 when that is positive, else 0, so
//    the zigzag between two faces of L is damped; Polyak's step toward the best upper bound along d_k, its factor
//    halved after 10 iterations without a better lower bound;
//  - reduced-cost fixing (relaxation_bound.hpp): whenever a bound improves, the tuples that can still be in a
//    solution better than the best one are counted at the best multipliers; once few remain (see kFixingTuples),
//    the branch and bound over them proves the optimum (or runs out of its budget and the iterations go on);
//  - it stops when the gap UB - LB is at most the tolerance, in cost units (the costs are negative log-likelihood
//    ratios, so nats).  Why absolute: a tuple's cost is mostly the constant -ln(P_D / (lambda 2 pi sigma^2)) per
//    detection (about -33 per tuple on the passive grid), the same for every assignment of the same detections,
//    while competing assignments differ by a few units of the variable part (1/2 chi2); a gap relative to |UB| let
//    the relaxation stop anywhere within ~6 units of a scan's optimum.
#include "assoc/relaxation_bound.hpp"
#include "assoc/relaxation_problem.hpp"

#include <vector>

namespace sextant::assoc {

/// Reduced-cost fixing hands the component to the branch and bound from iteration kFixingFirstIteration on, once
/// at most min(kFixingTuples, kFixingTuplesStart + kFixingTuplesPerIteration x iteration) tuples remain: the
/// search's cost grows steeply with the tuples, so early on only a small remainder is worth it, later a larger one
/// beats more iterations; and on small easy components a few more iterations close the gap for less than any
/// search.  Solver time on 60 scans each (seeds 1-3, bench/assoc/timing_driver.cpp's scenarios): grid 3 x 20 + 5
/// median 1.65 -> 1.53 ms against a fixed 150 tuples from the start (fixed 40, 80, 250: 1.60, 1.51 with a 20 %
/// higher mean, 3.28); uniform 3 x 20 + 5 with the target prior 0.11 -> 0.05 ms with the first iteration at 20
/// instead of 0 (the relaxation before fixing: 0.05).
inline constexpr size_t kFixingTuples = 150;
inline constexpr size_t kFixingTuplesStart = 60;
inline constexpr size_t kFixingTuplesPerIteration = 2;
inline constexpr int kFixingFirstIteration = 20;
/// The node budget of that branch and bound.
inline constexpr long kFixingNodes = 20'000;

struct ComponentResult {
  std::vector<int> chosen;  // positions in the component's group
  double ub = 0, lb = 0;
  int iterations = 0;
  Multipliers u;        // the relaxation's multipliers at its best lower bound
  RelaxedDual dual;     // the relaxed problem's solution there
  bool proven = false;  // lb == ub proven by an exact method
};

/// Runs the relaxation on P for at most `max_iterations` iterations; `gap_tolerance` in cost units.
ComponentResult solve_relaxation(const RelaxationProblem& P, int max_iterations, double gap_tolerance);

}  // namespace sextant::assoc
