#pragma once
// Primal recovery of the S-D Lagrangian relaxation (Deb, Yeddanapudi, Pattipati & Bar-Shalom, IEEE TAES 33(2)
// 1997, the recovery step): a feasible solution from the relaxed (sensor 1, sensor 2) assignment.  Its pairs are
// fixed and each further sensor q = 3..S is added by a 2-D assignment of the partial tuples against q's
// detections, the cost of extending a partial tuple by detection k being the best reduced cost (the multipliers of
// the sensors after q) of a tuple with that prefix and index; 0 for leaving it as it is.  The tuples are kept
// sorted (relaxation_problem.hpp), so the tuples extending a partial tuple are one contiguous range: its (sensor 1,
// sensor 2) pair group, looked up in a table, narrowed by binary search on the later indices.  Each stage is linear
// in the number of tuples.  (The table: a binary search over all the tuples for every partial tuple was 5 % of the
// solver's instructions on the 3 x 20 grid scans.)
//
// With three sensors the recovery does not depend on the multipliers (no sensor follows the third), only on the
// relaxed pairing: the relaxation skips it when a pairing recurs.
#include "assoc/assignment_with_missed.hpp"
#include "assoc/relaxation_problem.hpp"

#include <utility>
#include <vector>

namespace sextant::assoc {

/// Keeps its buffers from one call to the next (the relaxation recovers once per iteration).
class RelaxationRecovery {
 public:
  explicit RelaxationRecovery(const RelaxationProblem& P);

  /// The recovered tuples (sorted positions in P) into `chosen`, from the relaxed assignment `relaxed` (rows:
  /// sensor 1's detections, columns: sensor 2's) at multipliers u.
  void recover(const Multipliers& u, const MissedAssignment& relaxed, std::vector<int>& chosen);

 private:
  // The tuples whose first L >= 2 indices equal prefix[0 .. L).
  std::pair<int, int> range(const int* prefix, size_t L) const;

  const RelaxationProblem& P_;
  std::vector<std::pair<int, int>> pair_range_;  // per (a, b), a = 0..n_1, b = 0..n_2: its tuples ({0, 0}: none)
  std::vector<int> partial_;                     // partial tuples, S entries each (the later ones 0 until assigned)
  std::vector<PairCost> pairs_;
  std::vector<double> row_missed_, column_missed_;
  MissedAssignmentSolver solver_;
};

}  // namespace sextant::assoc
