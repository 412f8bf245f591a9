#pragma once
// Exact weighted set packing (the S-D assignment as set packing, tuple_packing.hpp): choose pairwise disjoint
// tuples of least total cost, uncovered detections costing 0.  Branch and bound on a Lagrangian bound.
//
// The bound.  Relaxing every detection's constraint "used at most once" with a multiplier v_d <= 0 gives
//   L(v) = sum_d v_d + sum_t min(0, r_t),   r_t = c_t - sum_{d in t} v_d  (the tuple's reduced cost),
// a lower bound on the optimum for ANY v <= 0 (each chosen tuple pays r_t + its members' v, each detection's v_d
// is counted once); its maximum over v is the packing LP's optimum (LP duality).  v is chosen once per problem,
// at the root, by subgradient ascent on L (maximize_packing_lagrangian) or from a caller's multipliers; the search
// is exact whatever v is, v only decides how much it prunes.
//
// The search.  A node has covered detections (taken by a chosen tuple, or declared false alarms) and the cost of
// its chosen tuples; a tuple is available when none of its detections is covered.  Its bound is
//   cost + sum over uncovered detections that some available tuple holds of v_d + sum over available t of min(0, r_t),
// which is L(v) of the remaining sub-problem (a detection no available tuple holds is a false alarm, and its v_d
// <= 0 would only loosen the bound), kept up to date incrementally as detections are covered and uncovered.  It
// branches on the uncovered detection held by the fewest available tuples (with a stronger bound, the fewest that
// its increases do not cut): each of those tuples (least reduced cost
// first: with multipliers near the LP optimum that follows the LP solution, so good incumbents come early), then the
// detection as a false alarm.  A node whose bound is not below the incumbent by more than 1e-9 (relative) is cut.
//
// Budget: at most `max_nodes` nodes.  When it runs out the answer is the incumbent, `proven` is false and
// `lower_bound` is the root bound; it is never reported as optimal.
#include "assoc/tuple_packing.hpp"

#include <functional>
#include <vector>

namespace sextant::assoc {

/// L(v) above (v has one entry per detection, each <= 0).
double packing_lagrangian(const TuplePacking& p, const std::vector<double>& v);

/// Subgradient ascent on L from `v` (resized to the detections and clipped to <= 0 first): Polyak steps toward
/// `upper` (a feasible solution's cost), the step factor halved after 10 iterations without a better bound; stops
/// when the bound reaches `upper` (within 1e-9 relative) or after `iterations`.  Leaves the best multipliers in
/// `v` and returns L there.
double maximize_packing_lagrangian(const TuplePacking& p, std::vector<double>& v, double upper, int iterations);

/// The equal shares v_d = min(0, min over tuples t holding d of c_t / |t|): a point where every r_t >= 0, so
/// L(v) = sum_d v_d (the bound the first branch and bound used alone).
std::vector<double> equal_share_multipliers(const TuplePacking& p);

struct PackingSolution {
  std::vector<int> chosen;  // tuple indices, sorted
  double cost = 0;
  double lower_bound = 0;  // the optimum when proven, else the root bound
  long nodes = 0;
  bool proven = false;  // the search finished within its budget: `cost` is the optimum
};

/// A stronger lower bound on the cost of a node's remaining sub-problem, given which detections are covered and,
/// per tuple, how many of its detections are (0: available).  Called only where the bound above does not cut.
/// When `increase` is not null it is filled (one entry per tuple) with, for each available tuple t, a lower bound
/// on how much more the bound is once t is chosen: the search then skips every child whose node bound plus its
/// increase already reaches the incumbent, without evaluating it (reduced-cost fixing at the node).
using NodeBound = std::function<double(const std::vector<char>& covered, const std::vector<int>& blocked,
                                       std::vector<double>* increase)>;

/// Branch and bound from the feasible solution `incumbent` (pairwise disjoint tuples; may be empty) with the
/// multipliers `v` (<= 0, one per detection) and, when given, `stronger` as a second bound.
PackingSolution solve_packing_exactly(const TuplePacking& p, const std::vector<int>& incumbent,
                                      const std::vector<double>& v, long max_nodes, const NodeBound& stronger = {});

}  // namespace sextant::assoc
