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

/// A hub (a variable with more than kHubFactors factors: a landmark seen from many keyframes, a keyframe that sees
/// many landmarks) whose relinearization alone would cost more than kHubRebuildAbove times
/// IncrementalOptions::relinearize_work is never relinearized by rank updates: each of its factors walks its own path
/// to the root, through the landmarks' dense block at the end of the factor, where a rebuild passes each column once.
/// One landmark seen from 57 keyframes took 35 ms in one update of a 3-D lifelong run (5.5 budgets).  A pose of a
/// pose graph (4 to 13 factors in the shared sets) is not a hub: torus3D's heaviest (up to 8 budgets) are cheaper by
/// rank updates in the tail (p99 97 against 114 ms when rebuilt; bench/results/incremental_isam2.md).
inline constexpr size_t kHubFactors = 16;
inline constexpr double kHubRebuildAbove = 2.0;

/// The variables of `moved` relinearized in this round: by how far their steps are past the thresholds, largest
/// first, as long as the rank-update work of their factors (the sum, over the factors, of residual dimension x the
/// column counts along the factor's path to the root) stays within IncrementalOptions::relinearize_work and their
/// factors number at most update_limit(); the first is taken even above the budget, but only at every
/// IncrementalOptions::heavy_relinearize_every-th update, and never a hub whose work alone is above kHubRebuildAbove
/// budgets: such a hub is left out and `too_heavy` set.  Appends their factors (each once) to `factors`.
std::vector<int> within_work_budget(const SmootherState& s, std::vector<int> moved, std::vector<size_t>& factors,
                                    bool* too_heavy = nullptr);

enum class Relinearized {
  kDone,           // the factors of `moved` are relinearized at the variables' estimates
  kTooMany,        // more factors than update_limit(), or a variable too heavy: nothing changed, the caller rebuilds
  kCholmodFailed,  // the factorization is no longer valid (s.cholmod_failure)
};
/// Relinearizes the factors of the variables within_work_budget() picks from `moved`; with `rebuild_if_many`, first
/// kTooMany when their factors number more than update_limit() or a hub among them is too heavy (kHubRebuildAbove);
/// without, a too heavy hub waits for the reordering under way, which relinearizes every factor.
Relinearized relinearize(SmootherState& s, const std::vector<int>& moved, IncrementalStatus& st, bool rebuild_if_many);

}  // namespace sextant::graph::smoother
