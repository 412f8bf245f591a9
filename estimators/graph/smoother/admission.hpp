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

/// The same for a rebuild, which takes every pending factor whose variables are then all in: marks the entering
/// variables in `in` (which holds the variables in the system and the fixed ones), gives the entering factors
/// weight 1 and leaves the others pending.  Counts them in `st`.
void admit_for_rebuild(SmootherState& s, std::vector<char>& in, IncrementalStatus& st);

}  // namespace sextant::graph::smoother
