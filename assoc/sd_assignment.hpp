#pragma once
// The S-D assignment of detections to targets (assoc.md §1.4): choose disjoint tuples (each detection in at most
// one tuple; the missed index 0 may repeat) minimizing the summed cost; detections in no tuple are false alarms
// (cost 0).
//  - Exact: branch and bound over the detections (each is in one of its tuples or a false alarm), bounded below by
//    sum over uncovered detections of min(0, min over its tuples of cost / size).  The oracle for small problems.
//  - Lagrangian relaxation (Pattipati et al. 1992; Deb et al. 1997; assoc.md §1.5): the constraints of sensors
//    3..S are relaxed with multipliers u_s; the relaxed problem is a 2-D assignment between sensors 1 and 2 whose
//    costs are the tuples' reduced costs minimized over the other indices (the all-missed pair takes every negative
//    reduced cost); its value is a lower bound.  A feasible solution is recovered by fixing the (1, 2) pairs and
//    assigning each further sensor by a 2-D assignment; its cost is an upper bound.  Multipliers follow Polyak's
//    subgradient step.  Stops when the relative gap (UB - LB) / |UB| falls below the tolerance.
#include "assoc/tuple_costs.hpp"

#include <vector>

namespace sextant::assoc {

struct SdSolution {
  std::vector<int> tuples;  // indices into the tuple list
  double cost = 0;          // upper bound (the solution's cost)
  double lower_bound = 0;   // best dual value (exact: equal to cost)
  double gap = 0;           // (cost - lower_bound) / |cost|, 0 when cost is 0
  int iterations = 0;
  bool exact = false;
};

/// `detections_per_sensor[s]` = n_s.
SdSolution solve_sd_exact(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                          long max_nodes = 50'000'000);

SdSolution solve_sd_lagrangian(const std::vector<Tuple>& tuples, const std::vector<int>& detections_per_sensor,
                               int max_iterations = 100, double gap_tolerance = 0.01);

}  // namespace sextant::assoc
