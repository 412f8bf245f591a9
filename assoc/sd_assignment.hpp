#pragma once
// The S-D assignment of detections to targets (assoc.md §1.4): choose disjoint tuples (each detection in at most
// one tuple; the missed index 0 may repeat) minimizing the summed cost; detections in no tuple are false alarms
// (cost 0).  Both solvers first split the tuples into independent components (tuple_packing.hpp) and solve each
// on its own; the reported cost, bound and gap are the sums over the components.
//  - Exact: branch and bound over the detections (each is in one of its tuples or a false alarm), bounded below by
//    sum over uncovered detections of min(0, min over its tuples of cost / size).  The oracle for small problems.
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
//      iterations without a better lower bound.  Stops when the relative gap (UB - LB) / |UB| falls below the
//      tolerance;
//    * a component still above the tolerance at the iteration limit is solved again with the sensor order rotated
//      (another sensor relaxed, so the recovery fixes another pair of sensors), up to twice; the best upper and
//      lower bounds of the runs count.
//    Components of at most 8 detections are solved exactly (branch and bound) instead: their LP bound is often
//    fractional (three pairs on three detections: 1/2 each), and no Lagrangian bound can close that gap.
#include "assoc/tuple_costs.hpp"

#include <vector>

namespace sextant::assoc {

struct SdSolution {
  std::vector<int> tuples;  // indices into the tuple list
  double cost = 0;          // upper bound (the solution's cost)
  double lower_bound = 0;   // best dual value (exact: equal to cost)
  double gap = 0;           // (cost - lower_bound) / |cost|, 0 when cost is 0
  int iterations = 0;       // the most relaxation iterations any component took (summed over its rotations)
  int components = 0;       // independent components
  int largest_component = 0;  // tuples in the largest one
  bool exact = false;
};

/// `detections_per_sensor[s]` = n_s.  `max_nodes` bounds the search over all components; `exact` is false when it
/// ran out (the solution is then the best found).
SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                          long max_nodes = 50'000'000);

SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                               int max_iterations = 100, double gap_tolerance = 0.01);

}  // namespace sextant::assoc
