#pragma once
// The marginal covariance of one variable from the incremental smoother's factor: the block of H^-1, H = L D L',
// by a forward solve along the variable's path to the root of the elimination tree (Gilbert 1994: the reach of a
// column is its path), so the newest variables (ordered last, near the root) cost a few columns however large the
// graph.  H = sum J' W J is the Fisher information of the estimate (Omega = covariance^-1): its covariance is H^-1.
#include "estimators/graph/smoother/smoother_state.hpp"

#include <Eigen/Core>

namespace sextant::graph::smoother {

/// In the variable's tangent space (translation first); empty for a fixed or not yet determined variable, or when
/// there is no factorization.
Eigen::MatrixXd marginal_covariance(SmootherState& s, int index);

}  // namespace sextant::graph::smoother
