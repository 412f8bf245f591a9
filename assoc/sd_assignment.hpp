#pragma once
// The S-D assignment of detections to targets (assoc.md §1.4): choose disjoint tuples (each detection in at most
// one tuple; the missed index 0 may repeat) minimizing the summed cost; detections in no tuple are false alarms
// (cost 0).  Both solvers first split the tuples into independent components (tuple_packing.hpp) and solve each
// on its own; the reported cost, bound and gap are the sums over the components.
//  - Exact: per component, the relaxation below (for an incumbent and multipliers), then branch and bound over the
//    detections (each is in one of its tuples or a false alarm; packing_branch_and_bound.hpp) cut by the packing's
//    Lagrangian bound and, with 3 or more sensors, by the relaxation's own bound at its best multipliers on each
//    node's sub-problem, within a node budget.  `exact` is true only when every
//    component's search finished: the cost is then the optimum.  When the budget runs out the solution is the best
//    found, `exact` is false and `lower_bound` is a valid bound (never a non-optimal answer marked exact).
//  - Lagrangian relaxation (Pattipati et al. 1992; Deb et al. 1997; assoc.md §1.5), per component with S' >= 3
//    sensors (a component seen by two sensors is a 2-D assignment, solved exactly):
//    * the sensors are ordered by decreasing detection count; the constraints of sensors 3..S' are relaxed with
//      multipliers u_s; the relaxed problem is a 2-D assignment between sensors 1 and 2 whose costs are the
//      tuples' reduced costs minimized over the other indices (the all-missed pair takes every negative reduced
//      cost); its value is a lower bound;
//    * recovery: the (1, 2) pairs are fixed and each further sensor is added by a 2-D assignment of the partial
//      tuples against its detections.  The tuples are kept sorted, so the tuples extending a partial tuple are one
//      contiguous range found by binary search: each recovery stage is linear in the number of tuples;
//    * the recovered solution is improved by local search: the first one by exchange moves (tuple_packing.hpp),
//      later ones that tie or beat the best by re-assigning one sensor at a time with the others fixed
//      (sensor_reassignment.hpp); the relaxed solution itself counts when it uses no detection twice; the best
//      solution is kept (upper bound);
//    * the multipliers start at each detection's smallest equal share c_t / m_t of the tuples holding it (a feasible
//      point of the packing LP's dual; far fewer iterations than starting at 0);
//    * multipliers follow Polyak's subgradient step toward the best upper bound, its factor halved after 10
//      iterations without a better lower bound.  Stops when the gap UB - LB falls below the tolerance, in cost
//      units (the costs are negative log-likelihood ratios, so in nats).  Why absolute: a tuple's cost is mostly the
//      constant -ln(P_D / (lambda 2 pi sigma^2)) per detection (about -33 per tuple on the passive grid), the same
//      for every assignment of the same detections, while competing assignments differ by a few units of the
//      variable part (1/2 chi2); a gap relative to |UB| let the relaxation stop anywhere within ~6 units of a
//      scan's optimum (RESULTS, "Correct by default");
//    * a component still above the tolerance at the iteration limit is solved again with the sensor order rotated
//      (another sensor relaxed, so the recovery fixes another pair of sensors), up to twice; the best upper and
//      lower bounds of the runs count;
//    * a component whose gap is still open then goes to the exact branch and bound (packing_branch_and_bound.hpp)
//      from the best solution, within a small node budget: it proves (or finds) the optimum where the LP bound is
//      fractional, which no Lagrangian multiplier can close.
//    Components of at most 8 detections are solved exactly (branch and bound) instead: their LP bound is often
//    fractional (three pairs on three detections: 1/2 each), and no Lagrangian bound can close that gap.
#include "assoc/tuple_costs.hpp"

#include <vector>

namespace sextant::assoc {

/// The relaxation's default stopping gap, in cost units (nats).
inline constexpr double kDefaultGapTolerance = 0.01;

struct SdSolution {
  std::vector<int> tuples;  // indices into the tuple list
  double cost = 0;          // upper bound (the solution's cost)
  double lower_bound = 0;   // best dual value (exact: equal to cost)
  double gap = 0;           // (cost - lower_bound) / |cost|, 0 when cost is 0 (reported; not the stopping rule)
  double absolute_gap = 0;  // cost - lower_bound, in cost units
  int iterations = 0;       // the most relaxation iterations any component took (summed over its rotations)
  int components = 0;       // independent components
  int largest_component = 0;  // tuples in the largest one
  bool exact = false;       // proven optimal: lower_bound equals cost (within 1e-9 relative)
};

/// `detections_per_sensor[s]` = n_s.  `max_nodes` bounds the search of each component; `exact` is false when one
/// ran out (the solution is then the best found, `lower_bound` a valid bound below the optimum).
SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                          long max_nodes = 200'000);

/// `gap_tolerance`: absolute, in cost units (see above).
SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                               int max_iterations = 100, double gap_tolerance = kDefaultGapTolerance);

}  // namespace sextant::assoc
