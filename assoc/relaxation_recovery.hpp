#pragma once
// Primal recovery of the S-D Lagrangian relaxation (Deb, Yeddanapudi, Pattipati & Bar-Shalom, IEEE TAES 33(2)
// 1997, the recovery step): a feasible solution from the relaxed (sensor 1, sensor 2) assignment.  Its pairs are
// fixed and each further sensor q = 3..S is added by a 2-D assignment of the partial tuples against q's
// detections, the cost of extending a partial tuple by detection k being the best reduced cost (the multipliers of
// the sensors after q) of a tuple with that prefix and index; 0 for leaving it as it is.  The tuples are kept
// sorted (relaxation_problem.hpp), so the tuples extending a partial tuple are one contiguous range found by binary
// search: each stage is linear in the number of tuples.
//
// With three sensors the recovery does not depend on the multipliers (no sensor follows the third), only on the
// relaxed pairing: the relaxation skips it when a pairing recurs.
#include "assoc/assignment_with_missed.hpp"
#include "assoc/relaxation_problem.hpp"

#include <vector>

namespace sextant::assoc {

/// Keeps its buffers from one call to the next (the relaxation recovers once per iteration).
class RelaxationRecovery {
 public:
  explicit RelaxationRecovery(const RelaxationProblem& P) : P_(P) {}

  /// The recovered tuples (sorted positions in P) into `chosen`, from the relaxed assignment `relaxed` (rows:
  /// sensor 1's detections, columns: sensor 2's) at multipliers u.
  void recover(const Multipliers& u, const MissedAssignment& relaxed, std::vector<int>& chosen);

 private:
  const RelaxationProblem& P_;
  std::vector<int> partial_;  // partial tuples, S entries each (the later ones 0 until assigned)
  std::vector<PairCost> pairs_;
  std::vector<double> row_missed_, column_missed_;
  MissedAssignmentSolver solver_;
};

}  // namespace sextant::assoc
