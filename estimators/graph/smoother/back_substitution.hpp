#pragma once
// The back half of the solve, dx = (L D L')^-1 (-g) from y = L^-1 (-g) (kept current by the rank updates): the
// back-substitution L' dx = D^-1 y with iSAM2's wildfire (Kaess et al., IJRR 2012, Alg. 7) at column granularity.
// A column is recomputed when CHOLMOD modified it or when a column in its structure moved by more than
// IncrementalOptions::wildfire since that column last propagated; a column that is not recomputed cuts off its
// subtree.  Then the estimates x = x0 (+) dx of the variables whose step changed.
#include "estimators/graph/smoother/smoother_state.hpp"

namespace sextant::graph::smoother {

/// `full`: every column, exactly (iSAM2's calculateBestEstimate); else the wildfire's columns only.
void back_substitute(SmootherState& s, bool full);

}  // namespace sextant::graph::smoother
