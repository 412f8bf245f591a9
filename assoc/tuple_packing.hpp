#pragma once
// The S-D assignment seen as weighted set packing: each tuple is the set of detections it uses (the missed index
// is no detection), a solution is a set of pairwise disjoint tuples, its cost the sum of theirs (uncovered
// detections are false alarms at cost 0).  Two mechanisms the S-D solvers share:
//  - independent components: tuples that share no detection, directly or through other tuples, can be solved
//    separately (union-find over the detections);
//  - exchange improvement of a feasible solution (the primal step after the Lagrangian recovery): bring in one
//    tuple, drop the chosen tuples it conflicts with, refill the freed detections greedily with the cheapest
//    tuples that fit; keep the move when the total cost falls.  Repeated until no move improves.
#include <initializer_list>
#include <span>
#include <vector>

namespace sextant::assoc {

/// The tuples in one flat array: tuple t holds the detection ids ids[begin[t] .. begin[t + 1]).
struct TuplePacking {
  int detections = 0;            // detection ids are 0..detections-1
  std::vector<int> begin = {0};  // per tuple, where its ids start; one more entry than tuples
  std::vector<int> ids;
  std::vector<double> cost;  // per tuple

  /// Appends a tuple (distinct ids in 0..detections-1) of cost `tuple_cost`.
  void add(std::span<const int> members, double tuple_cost) {
    ids.insert(ids.end(), members.begin(), members.end());
    begin.push_back(static_cast<int>(ids.size()));
    cost.push_back(tuple_cost);
  }
  void add(std::initializer_list<int> members, double tuple_cost) {
    add(std::span<const int>(members.begin(), members.size()), tuple_cost);
  }
  size_t size() const { return cost.size(); }
  std::span<const int> members(size_t t) const {
    return {ids.data() + begin[t], static_cast<size_t>(begin[t + 1] - begin[t])};
  }
};

/// Groups of tuple indices, one per independent component (in order of their first tuple).
std::vector<std::vector<int>> independent_components(const TuplePacking& p);

/// Exchange improvement over one fixed tuple list (the per-list preparation is done once, then `improve` runs on
/// each candidate solution).  A move is evaluated only when it can pay: its gain is bounded below by the tuple's
/// cost minus the dropped ones plus, per freed detection, the cheapest tuple containing it; the refill looks at
/// the `refill_candidates` cheapest tuples of each freed detection.
///
/// Speed: a tuple is evaluated again in a later sweep only after a move changed the owner of one of its
/// detections ("don't look" marks; a tuple whose move was rejected in its refill is not retried while its own
/// detections keep their owners, although other moves may have changed what its refill could find); the tuples
/// are stored cheapest first in flat arrays.
class ExchangeImprover {
 public:
  explicit ExchangeImprover(const TuplePacking& p, int refill_candidates = 16);
  /// Improves `chosen` (indices of pairwise disjoint tuples) in place; returns its cost.  At most `max_passes`
  /// sweeps over the tuples.
  double improve(std::vector<int>& chosen, int max_passes = 20);

 private:
  // improve's steps.
  void load(const std::vector<int>& chosen);
  bool try_move(int t);
  double refill_freed(int t, long stamp, double delta, double bound);
  void apply_move(int t);
  void touched(int d);
  double unload(std::vector<int>& chosen) const;

  // Tuples are addressed by rank: 0..negative_-1 the tuples of negative cost, cheapest first, then the others.
  int refill_candidates_;
  int negative_ = 0;
  std::vector<int> tuple_of_rank_, rank_of_tuple_;
  std::vector<double> cost_;                            // by rank
  std::vector<int> member_begin_, members_;             // by rank: members_[member_begin_[r] .. member_begin_[r + 1])
  std::vector<int> of_detection_begin_, of_detection_;  // per detection, the ranks of its negative tuples, ascending
  std::vector<double> cheapest_;                        // per detection, min(0, the cheapest tuple containing it)
  std::vector<int> owner_;                              // per detection, the rank of the chosen tuple holding it, or -1
  std::vector<char> in_, look_;                         // by rank: chosen; to be evaluated in the next sweep
  std::vector<long> dropped_;                           // by rank: stamp of the evaluation that drops it
  std::vector<long> blocked_, freed_, counted_;  // per detection: stamp of the evaluation that takes / frees it /
                                                 // has taken its refill bound
  long stamp_ = 0;
  std::vector<int> conflicts_, freed_ids_, refill_;  // of the move being evaluated
};

/// ExchangeImprover(p).improve(chosen, max_passes).
double improve_by_exchange(const TuplePacking& p, std::vector<int>& chosen, int max_passes = 20);

}  // namespace sextant::assoc
