#pragma once
// The S-D assignment of detections to targets (Pattipati, Deb, Bar-Shalom & Washburn, IEEE TAC 37(2) 1992, the
// problem (P)): choose disjoint tuples (each detection in at most one tuple; the missed index 0 may repeat)
// minimizing the summed cost; detections in no tuple are false alarms (cost 0).  Both solvers first split the tuples
// into independent components (tuple_packing.hpp) and solve each on its own; the reported cost, bound and gap are
// the sums over the components.  The steps, each in its own file:
//  - relaxation_problem.hpp: a component restated for the relaxation (sensors reordered, tuples sorted);
//  - lagrangian_relaxation.hpp: the relaxation itself (deflected subgradient on the multipliers of sensors 3..S,
//    recovery and local search for upper bounds, reduced-cost fixing once the bounds are close);
//  - relaxation_recovery.hpp: the primal recovery;
//  - relaxation_bound.hpp: the bound at fixed multipliers on a branch and bound node, reduced-cost fixing, and the
//    branch and bound over the tuples it leaves (packing_branch_and_bound.hpp).
// The solvers:
//  - Exact: per component, the relaxation (for an incumbent and multipliers), then the branch and bound over the
//    tuples reduced-cost fixing leaves, cut by the relaxation's bound on each node's sub-problem, within a node
//    budget.  `exact` is true only when every component's search finished: the cost is then the optimum.  When the
//    budget runs out the solution is the best found, `exact` is false and `lower_bound` is a valid bound (never a
//    non-optimal answer marked exact).
//  - Lagrangian relaxation, per component with S' >= 3 sensors (a component seen by two sensors is a 2-D
//    assignment, solved exactly; one of at most 8 detections goes to the branch and bound directly, its LP bound
//    being often fractional).  It stops when the gap UB - LB is at most the tolerance, in cost units (nats; why
//    absolute: lagrangian_relaxation.hpp), or when the branch and bound over the tuples left by reduced-cost fixing
//    proves the optimum.  A component still above the tolerance at the iteration limit is solved again with the
//    sensor order rotated (another sensor relaxed), up to twice, then goes to that branch and bound (at the
//    multipliers of the run with the best bound) within a small node budget: it proves (or finds) the optimum where
//    the LP bound is fractional, which no multiplier can close.  The exact solver ends the same way, with its own
//    budget.
#include "assoc/tuple_costs.hpp"

#include <vector>

namespace sextant::assoc {

/// The relaxation's default stopping gap, in cost units (nats).
inline constexpr double kDefaultGapTolerance = 0.01;

struct SdSolution {
  std::vector<int> tuples;    // indices into the tuple list
  double cost = 0;            // upper bound (the solution's cost)
  double lower_bound = 0;     // best dual value (exact: equal to cost)
  double gap = 0;             // (cost - lower_bound) / |cost|, 0 when cost is 0 (reported; not the stopping rule)
  double absolute_gap = 0;    // cost - lower_bound, in cost units
  int iterations = 0;         // the most relaxation iterations any component took (summed over its rotations)
  int components = 0;         // independent components
  int largest_component = 0;  // tuples in the largest one
  bool exact = false;         // proven optimal: lower_bound equals cost (within 1e-9 relative)
};

/// `detections_per_sensor[s]` = n_s.  `max_nodes` bounds the search of each component; `exact` is false when one
/// ran out (the solution is then the best found, `lower_bound` a valid bound below the optimum).
SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                          long max_nodes = 200'000);

/// `gap_tolerance`: absolute, in cost units (see above).
SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                               int max_iterations = 100, double gap_tolerance = kDefaultGapTolerance);

}  // namespace sextant::assoc
