#pragma once
// Fluid relinearization (Kaess et al., "iSAM2: Incremental smoothing and mapping using the Bayes tree", IJRR 2012,
// Alg. 6 at variable granularity): every variable whose step |dx_v| exceeds the thresholds moves its linearization
// point, x0_v <- x0_v (+) dx_v, and each factor touching it is downdated at its old linearization and updated at the
// new one, by rank updates (rank_update.hpp).
#include "estimators/graph/smoother/smoother_state.hpp"

#include <cstddef>
#include <vector>

namespace sextant::graph::smoother {

/// The variables in the system whose step exceeds relinearize_translation or relinearize_rotation in a component.
std::vector<int> moved_variables(const SmootherState& s);

/// Factors changed by rank updates in one round beyond which a rebuild is cheaper (IncrementalOptions::update_fraction).
size_t update_limit(const SmootherState& s);

/// The variables of `moved` relinearized in this round: by how far their steps are past the thresholds, largest
/// first, as long as the rank-update work of their factors (the sum, over the factors, of residual dimension x the
/// column counts along the factor's path to the root) stays within IncrementalOptions::relinearize_work and their
/// factors number at most update_limit(); the first is always taken.  Appends their factors (each once) to `factors`.
std::vector<int> within_work_budget(const SmootherState& s, std::vector<int> moved, std::vector<size_t>& factors);

enum class Relinearized {
  kDone,           // the factors of `moved` are relinearized at the variables' estimates
  kTooMany,        // more factors than update_limit(): nothing changed, the caller rebuilds
  kCholmodFailed,  // the factorization is no longer valid (s.cholmod_failure)
};
/// Relinearizes the factors of the variables within_work_budget() picks from `moved`; with `rebuild_if_many`, first
/// kTooMany when their factors number more than update_limit().
Relinearized relinearize(SmootherState& s, const std::vector<int>& moved, IncrementalStatus& st, bool rebuild_if_many);

}  // namespace sextant::graph::smoother
