#pragma once
// Local search on a feasible S-D assignment by "dimension-wise variation" (Bandelt, Maas & Spieksma 2004, "Local
// search heuristics for multi-index assignment problems with decomposable costs", JORS 55; Karapetyan & Gutin 2011,
// "Local search heuristics for the multidimensional assignment problem", J. Heuristics 17, §3.2): keep every
// sensor's part of the solution but one, and re-assign that sensor's detections optimally.
//
// With sensor s left out, each chosen tuple leaves a "rest" (its indices at the other sensors); every detection of
// another sensor that no chosen tuple holds is a rest of its own.  Re-assigning sensor s is then a 2-D assignment of
// rests against sensor s's detections: pairing rest r with detection k costs the tuple (r, k at s) when it is in the
// list; leaving rest r unpaired costs the tuple (r, missed at s) when it is in the list, else 0 (its detections
// become false alarms); an unpaired detection is a false alarm (0).  The current solution is one assignment of this
// problem, so the optimum never costs more; the sensors are taken in turn until none improves.
//
// Why: the exchange moves (tuple_packing.hpp) bring in one tuple at a time and refill greedily, so they miss moves
// in which several tuples swap detections of the same sensor at once (e.g. three tuples rotating their third
// sensor's detections).  Those were the Lagrangian relaxation's misses against the exact optimum on the coplanar
// grid (bench/RESULTS.md, "Passive association", LR optimality).  One re-assignment is a sparse 2-D assignment of about as many
// rows as chosen tuples plus free detections: cheap next to a relaxation iteration.
#include "assoc/assignment_with_missed.hpp"

#include <cstddef>
#include <utility>
#include <vector>

namespace sextant::assoc {

class SensorReassignment {
 public:
  /// The tuple list: tuple t has index[t * S + s] at sensor s (0 = missed, k = detection k of n[s]); cost[t] its
  /// cost; the index vectors sorted lexicographically and distinct (std::invalid_argument otherwise).  The vectors are referenced, not copied: they must outlive this object.
  SensorReassignment(size_t sensors, const std::vector<int>& n, const std::vector<int>& index,
                     const std::vector<double>& cost);

  /// Improves `chosen` (indices of pairwise disjoint tuples) in place by re-assigning one sensor at a time until a
  /// full round over the sensors improves nothing (at most `max_rounds` rounds); returns its cost (summed in
  /// ascending tuple order).
  double improve(std::vector<int>& chosen, int max_rounds = 4);

 private:
  bool reassign(size_t s, std::vector<int>& chosen, double& cost);
  void sort_runs(size_t s);  // order_[s] from the identity: sorted by (rest, index at s)

  size_t S_;
  const std::vector<int>& n_;
  const std::vector<int>& index_;
  const std::vector<double>& cost_;
  std::vector<int> offset_;  // first detection id of each sensor (detections numbered across sensors)
  // Per sensor s, the tuples grouped by their rest (indices at the other sensors): order_[s] lists the tuples by
  // (rest, index at s), group g of sensor s is order_[s][group_begin_[s][g] .. group_begin_[s][g + 1]).
  std::vector<std::vector<int>> order_, group_begin_;
  std::vector<std::vector<int>> group_of_;      // per sensor, per tuple: its rest's group
  std::vector<std::vector<int>> single_group_;  // per sensor, per detection id: the group whose rest is that
                                                // detection alone, or -1
  // Working memory, reused between calls.
  std::vector<int> rows_;            // per rest: its group
  std::vector<int> unpaired_tuple_;  // per rest: the tuple (rest, missed at s), or -1
  std::vector<int> pair_tuple_;      // per pair: its tuple
  std::vector<char> covered_;        // per detection id: held by a chosen tuple
  std::vector<double> row_missed_, column_missed_;
  std::vector<PairCost> pairs_;
  std::vector<std::pair<unsigned long long, int>> keys_;
  MissedAssignmentSolver solver_;
};

}  // namespace sextant::assoc
