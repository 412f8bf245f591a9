// The incremental smoother's numeric factorization in slices.  The positions are the ordering, so CHOLMOD analyzes
// and factorizes in the natural order.  The factorization is up-looking, row by row (cholmod_rowfac): rows [0, k) of
// L depend only on rows [0, k) of H, so it stops and resumes at any row, and the slices give the factor one call
// would.
#include "estimators/graph/smoother/linear_system.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <algorithm>
#include <string>

namespace sextant::graph::smoother {

namespace {

// The work of each row of the up-looking factorization, as prefix sums (prefix[k]: rows [0, k)), so that a slice
// can take the rows that fit in the time it has: cholmod_rowfac's row k is a sparse triangular solve that, for every
// column j in the pattern of row k of L, does one multiply-add per entry of column j above row k.  Row costs are
// far from even: the last rows of a 3-D graph's factor reach a dense block of a thousand or more columns, where 96
// rows took 50-80 ms against well under a millisecond for 96 rows early on.  The patterns come from the elimination
// tree (a row's pattern is the union of the tree paths from its entries in H up to it), in O(nnz(L)).  Empty when
// CHOLMOD cannot compute the tree.
std::vector<double> row_work_prefix(cholmod_sparse& H, cholmod_common& common) {
  const size_t n = H.ncol;
  std::vector<int> parent(n);
  if (!cholmod_etree(&H, parent.data(), &common)) return {};
  const int* Hp = static_cast<const int*>(H.p);
  const int* Hi = static_cast<const int*>(H.i);
  const int* Hnz = static_cast<const int*>(H.nz);
  std::vector<int> mark(n, -1);
  std::vector<double> above(n, 0.0);  // per column j: entries of L's column j in the rows done so far
  std::vector<double> prefix(n + 1, 0.0);
  for (size_t k = 0; k < n; ++k) {
    const int row = static_cast<int>(k);
    const int end = H.packed ? Hp[k + 1] : Hp[k] + Hnz[k];
    double work = 1.0 + (end - Hp[k]);
    mark[k] = row;
    for (int p = Hp[k]; p < end; ++p)
      for (int j = Hi[p]; j >= 0 && j < row && mark[static_cast<size_t>(j)] != row;
           j = parent[static_cast<size_t>(j)]) {
        mark[static_cast<size_t>(j)] = row;
        work += above[static_cast<size_t>(j)]++;
      }
    prefix[k + 1] = prefix[k] + work;
  }
  return prefix;
}

// The rows after `first` whose work fits in `budget` (at least one).
size_t rows_within(const std::vector<double>& prefix, size_t first, double budget) {
  const auto last =
      std::upper_bound(prefix.begin() + static_cast<std::ptrdiff_t>(first) + 1, prefix.end(), prefix[first] + budget);
  return std::max<size_t>(1, static_cast<size_t>(last - prefix.begin()) - 1 - first);
}

// Where this slice's call of cholmod_rowfac stops: the rows whose work fits in the `left` ms of the slice at the
// rate the earlier calls ran (the first call takes a small amount, to measure it), so that a slice ends near its
// deadline in one or two calls, each of which costs a pass over CHOLMOD's workspace.
size_t sliced_call_end(System& sys, double left, cholmod_common& common) {
  const size_t n = static_cast<size_t>(sys.capacity);
  if (sys.row_work.empty()) sys.row_work = row_work_prefix(*sys.H, common);
  if (sys.row_work.empty()) return std::min(sys.factorized + 96, n);  // no tree: a fixed count
  constexpr double kFirstCall = 2e4;                                  // multiply-adds: well under a millisecond
  const double rate = sys.sliced_ms > 0 ? sys.sliced_work / sys.sliced_ms : 0.0;  // per ms
  const double budget = rate > 0 ? 0.9 * rate * left : kFirstCall;
  return std::min(sys.factorized + rows_within(sys.row_work, sys.factorized, budget), n);
}

}  // namespace

bool advance(SmootherState& s, System& sys, const std::function<double()>& ms_left) {
  constexpr size_t kFactorsPerSlice = 512;  // between looks at the clock: well under a millisecond each
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
    const double left = ms_left ? ms_left() : 0.0;
    if (ms_left && left <= 0) return false;
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
      const size_t end = ms_left ? sliced_call_end(sys, left, common) : n;  // sliced only when a deadline can stop it
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
      if (ms_left && !sys.row_work.empty()) {
        sys.sliced_work += sys.row_work[end] - sys.row_work[sys.factorized];
        sys.sliced_ms += left - ms_left();
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
