#pragma once
// Rank updates of the incremental smoother's factor (Davis and Hager, "Multiple-rank modifications of a sparse
// Cholesky factorization", SIMAX 2001, through cholmod_updown_solve): a factor f adds its normal-equation terms
// H_f = C C' and g_f to H = L D L' and g without refactorizing, and the forward solve y = L^-1 (-g) is carried along.
// Before a modification that could make CHOLMOD reallocate L, the storage is packed in place (make_room in the .cpp).
#include "estimators/graph/smoother/admission.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <Eigen/Core>

#include <vector>

namespace sextant::graph::smoother {

/// One factor's share of the normal equations at the linearization point: H_f = C C', g_f = grad, where
/// C' = U J over the factor's free columns (W = U'U, W = w Omega with the robust weight w).
struct Contribution {
  std::vector<int> cols;  // ascending
  Eigen::MatrixXd Ct;     // residual_dim x cols.size()
  Eigen::VectorXd grad;   // cols.size()
};
Contribution linearize(const SmootherState& s, size_t factor);

/// Adds (or removes) the contributions by one rank-k modification of L, and marks the columns it modified dirty.
/// `within_pattern`: C C' lies in the pattern L L' already has (a relinearized factor, a reserved column's identity),
/// so nothing fills in and L needs no room (Davis and Hager 2001: the new pattern of a column is its old one and the
/// rows C brings along its path).  False when CHOLMOD fails (s.cholmod_failure says what).
bool apply(SmootherState& s, const std::vector<Contribution>& cs, bool add, bool within_pattern = false);

/// Brings the admitted variables and factors into the factorized system: the variables take reserved columns, the
/// factors are added by one rank update and each new column's identity is removed by a downdate.  `definite`: every
/// new column kept a positive pivot (else the caller rebuilds).  False when CHOLMOD fails.
bool enter_by_rank_updates(SmootherState& s, const Admission& a, bool& definite);

}  // namespace sextant::graph::smoother
