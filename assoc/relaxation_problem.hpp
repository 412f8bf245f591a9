#pragma once
// One independent component of an S-D assignment restated for the Lagrangian relaxation (Pattipati, Deb,
// Bar-Shalom & Washburn, IEEE TAC 37(2) 1992; Deb, Yeddanapudi, Pattipati & Bar-Shalom, IEEE TAES 33(2) 1997):
// only the sensors that have detections in it, ordered by decreasing detection count (then rotated, see below),
// their detections renumbered 1..n_s, the tuples sorted lexicographically by their indices and stored flat (tuple
// t's index at sensor q is at(t, q); 0 = missed).  Sensors 1 and 2 of this order form the relaxed 2-D problem; the
// constraints of sensors 3..S are relaxed with multipliers u[q][k] (q >= 2, k = 1..n_q; u[q][0] = 0).
#include "assoc/tuple_costs.hpp"
#include "assoc/tuple_packing.hpp"

#include <utility>
#include <vector>

namespace sextant::assoc {

/// u[q][k]: the multiplier of detection k of (reordered) sensor q; rows 0 and 1 and entry 0 of each row stay 0.
using Multipliers = std::vector<std::vector<double>>;

struct RelaxationProblem {
  size_t S = 0;            // sensors
  std::vector<int> n;      // detections per (reordered) sensor
  std::vector<int> index;  // per tuple, S indices; rows sorted
  std::vector<double> cost;
  std::vector<int> original;  // position in the component's group
  std::vector<int> offset;    // detection k >= 1 of sensor q is detection offset[q] + k - 1 of `packing`
  TuplePacking packing;       // the same tuples (same order) as detection sets

  /// The tuples `group` (indices into `tuples`; `detections[s]` = n_s of the scan).  `rotation`: the sensors,
  /// ordered by decreasing detection count, are rotated left by this many places (the first two are the relaxed
  /// problem's, the others are relaxed).
  RelaxationProblem(const std::vector<Tuple>& tuples, const std::vector<int>& group, const std::vector<int>& detections,
                    size_t rotation = 0);

  size_t sensors() const { return S; }
  size_t size() const { return cost.size(); }
  int at(size_t t, size_t q) const { return index[t * S + q]; }

  /// The contiguous range [first, second) of tuples whose first L indices equal prefix[0 .. L), searched within
  /// [lo, hi) (by default all tuples; a narrower window must hold that whole range).
  std::pair<int, int> range(const int* prefix, size_t L, int lo = 0, int hi = -1) const;

  /// Tuples with the same (sensor 1, sensor 2) indices (a, b; 0 = missed), contiguous in the sorted order.
  struct PairGroup {
    int a, b, lo, hi;
  };
  std::vector<PairGroup> pair_groups() const;

  /// Zero multipliers of the right shape.
  Multipliers zero_multipliers() const;

  /// Each tuple's reduced cost c_t - sum over relaxed sensors q of u[q][index], into `reduced` (one per tuple).
  void reduced_costs(const Multipliers& u, std::vector<double>& reduced) const;
};

}  // namespace sextant::assoc
