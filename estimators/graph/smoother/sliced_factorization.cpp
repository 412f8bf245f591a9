// The incremental smoother's numeric factorization in slices.  The positions are the ordering, so CHOLMOD analyzes
// and factorizes in the natural order.  The factorization is up-looking, row by row (cholmod_rowfac): rows [0, k) of
// L depend only on rows [0, k) of H, so it stops and resumes at any row, and the slices give the factor one call
// would.
#include "estimators/graph/smoother/linear_system.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <algorithm>
#include <string>

namespace sextant::graph::smoother {

bool advance(SmootherState& s, System& sys, const std::function<bool()>& out_of_time) {
  constexpr size_t kFactorsPerSlice = 512;  // between looks at the clock: well under a millisecond each
  constexpr size_t kRowsPerSlice = 96;
  const size_t n = static_cast<size_t>(sys.capacity);
  cholmod_common& common = *s.workspace;
  auto fail = [&](std::string why, SmootherFailure failure) {
    sys.error = std::move(why);
    sys.failure = failure;
    sys.done = true;
    common.status = CHOLMOD_OK;
    return true;
  };
  auto cholmod_failed = [&](const std::string& what) {
    return fail(what + " (CHOLMOD status " + std::to_string(common.status) + ")", SmootherFailure::kFactorization);
  };
  while (!sys.done) {
    if (out_of_time && out_of_time()) return false;
    if (sys.assembled < sys.factors.size()) {
      assemble_values(s, sys, std::min(sys.assembled + kFactorsPerSlice, sys.factors.size()));
    } else if (sys.L == nullptr) {
      common.nmethods = 1;
      common.method[0].ordering = CHOLMOD_NATURAL;
      common.postorder = 0;
      common.supernodal = CHOLMOD_SIMPLICIAL;  // measured: the supernodal factor stores its relaxed
      // supernodes' zeros, which every later update and solve pays for, and ATLAS is slow on the small supernodes
      common.final_ll = 0;
      common.quick_return_if_not_posdef = 1;
      sys.L = own(cholmod_analyze(sys.H.get(), &common), s.workspace);
      if (sys.L == nullptr) return cholmod_failed("CHOLMOD symbolic analysis failed");
    } else if (sys.factorized < n) {
      // Sliced only when a deadline can stop it: each call costs a pass over CHOLMOD's workspace.
      const size_t end = !out_of_time ? n : std::min(sys.factorized + kRowsPerSlice, n);
      double beta[2] = {0.0, 0.0};
      // As cholmod_factorize does: the first call turns the symbolic factor into a numeric one with exactly the
      // space the column counts need (grow2 = 0); later updates grow it through make_room (rank_update.cpp).
      const size_t grow2 = common.grow2;
      if (sys.factorized == 0) sys.L->is_ll = 0, common.grow2 = 0;
      const bool ok = !s.workspace.take_fault() &&
                      cholmod_rowfac(sys.H.get(), nullptr, beta, sys.factorized, end, sys.L.get(), &common);
      common.grow2 = grow2;
      if (!ok) return cholmod_failed("CHOLMOD's numeric factorization failed");
      if (common.status == CHOLMOD_NOT_POSDEF || sys.L->minor < sys.L->n) {
        const size_t col = sys.L->minor < sys.L->n ? sys.L->minor : sys.factorized;
        const int var = col < sys.col_var.size() ? sys.col_var[col] : -1;
        return fail(
            "the normal equations are not positive definite: variable " +
                (var >= 0 ? std::to_string(s.graph.variables()[static_cast<size_t>(var)].id) : std::string("?")) +
                " is not determined by the factors (under-constrained, or disconnected from the gauge)",
            SmootherFailure::kUnderdetermined);
      }
      sys.factorized = end;
    } else {
      sys.H.reset();
      if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, sys.L.get(), &common))  // LDL', packed, monotonic
        return cholmod_failed("CHOLMOD could not convert the factor to LDL' form");
      // y = L^-1 b, b = -g: the forward half of the solve, kept current by every later update (cholmod_updown_solve).
      DensePtr b = own(cholmod_zeros(n, 1, CHOLMOD_REAL, &common), s.workspace);
      if (b == nullptr) return cholmod_failed("CHOLMOD could not allocate the right-hand side");
      for (size_t i = 0; i < n; ++i) static_cast<double*>(b->x)[i] = -sys.g[static_cast<Eigen::Index>(i)];
      sys.y = own(cholmod_solve(CHOLMOD_L, sys.L.get(), b.get(), &common), s.workspace);
      if (sys.y == nullptr) return cholmod_failed("CHOLMOD's forward solve failed");
      sys.done = true;
    }
  }
  return true;
}

}  // namespace sextant::graph::smoother
