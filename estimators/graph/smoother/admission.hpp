#pragma once
// Admission of new variables and factors into the incremental smoother's system, and the gauge.
//  - The gauge: without a fixed variable or a factor that fixes the gauge (a prior, Factor::fixes_gauge), the first
//    pose is held fixed, as the batch optimizer does.
//  - A pending factor enters when all its variables are in the system (or enter with it); a new variable enters when
//    the information its entering factors give it, sum J' Omega J over its block, is positive definite, so that the
//    system stays positive definite (a bearing-only sighting alone, say, waits for a second one).
#include "estimators/graph/smoother/smoother_state.hpp"

#include <vector>

namespace sextant::graph::smoother {

/// Fixes the gauge once, at the first update with variables.
void hold_gauge(SmootherState& s);

/// Which of the pending variables and factors enter at an update.
struct Admission {
  std::vector<int> vars_in, vars_wait;  // pending variables that enter now, and those that wait
  std::vector<size_t> factors_in, factors_wait;
  int new_dim = 0;  // columns the entering free variables take
};
Admission admit(const SmootherState& s);

/// The same for a new system built from scratch (a rebuild, a first build): every variable in the system is
/// relinearized at its current estimate; the pending variables their factors determine enter, and every pending
/// factor whose variables are then all in (entering factors get weight 1, the others stay pending).  Returns the
/// variables of the new system (those in it, the entering ones and the fixed ones); counts the entering in `st`.
std::vector<char> admit_for_rebuild(SmootherState& s, IncrementalStatus& st);

}  // namespace sextant::graph::smoother
