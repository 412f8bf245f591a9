#include "estimators/graph/smoother/back_substitution.hpp"

#include <algorithm>
#include <cmath>

namespace sextant::graph::smoother {

namespace {

// sum over k in [first, end) of Lx[k] dx[Li[k]], in four independent partial sums, so that the multiply-adds of a
// long column (a 3-D graph's factor has a dense top of a thousand columns and more) do not each wait for the last.
double column_dot(const double* Lx, const int* Li, int first, int end, const Eigen::VectorXd& dx) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
  int k = first;
  for (; k + 4 <= end; k += 4) {
    s0 += Lx[k] * dx[Li[k]];
    s1 += Lx[k + 1] * dx[Li[k + 1]];
    s2 += Lx[k + 2] * dx[Li[k + 2]];
    s3 += Lx[k + 3] * dx[Li[k + 3]];
  }
  for (; k < end; ++k) s0 += Lx[k] * dx[Li[k]];
  return (s0 + s1) + (s2 + s3);
}

}  // namespace

void back_substitute(SmootherState& s, bool full) {
  Factorization& fx = s.fx;
  if (fx.L == nullptr || fx.capacity == 0) return;
  const int* Lp = static_cast<const int*>(fx.L->p);
  const int* Li = static_cast<const int*>(fx.L->i);
  const int* Lnz = static_cast<const int*>(fx.L->nz);
  const double* Lx = static_cast<const double*>(fx.L->x);
  const double* y = static_cast<const double*>(fx.y->x);
  // From the root down (a parent's column index exceeds its children's).  A column that is not recomputed cuts off
  // its subtree: a descendant's structure above it lies in its own structure (the row-subtree property of L), and no
  // descendant of an unmodified column is modified.
  std::fill(fx.recomputed.begin(), fx.recomputed.end(), 0);
  std::fill(fx.changed.begin(), fx.changed.end(), 0);
  s.var_changed.assign(s.graph.variables().size(), 0);
  const double threshold = full ? -1.0 : s.options.wildfire;
  for (int j = fx.capacity - 1; j >= 0; --j) {  // the hubs' columns too, after the reserved ones
    const size_t ju = static_cast<size_t>(j);
    const int first = Lp[j] + 1, end = Lp[j] + Lnz[j], parent = fx.parent_of(j);
    if (parent >= 0 && !fx.recomputed[static_cast<size_t>(parent)]) continue;
    bool need = full || fx.dirty[ju];
    // From the highest row down: the rows most likely to have changed (the hubs, ordered last, and the newest poses)
    // are a column's last, so the scan usually stops at once.
    for (int k = end - 1; !need && k >= first; --k) need = fx.changed[static_cast<size_t>(Li[k])] != 0;
    if (!need) continue;
    const double x = y[j] / Lx[Lp[j]] - column_dot(Lx, Li, first, end, fx.dx);
    fx.recomputed[ju] = 1;
    if (x != fx.dx[j] && fx.col_var[ju] >= 0) s.var_changed[static_cast<size_t>(fx.col_var[ju])] = 1;
    fx.dx[j] = x;
    // Compared with the value its dependants last saw, so that small changes cannot accumulate unseen.
    if (std::abs(x - fx.seen[ju]) > threshold) fx.changed[ju] = 1, fx.seen[ju] = x;
  }
  std::fill(fx.dirty.begin(), fx.dirty.end(), 0);
  auto& vars = s.graph.variables();
  if (s.estimate_moved.size() < vars.size()) s.estimate_moved.resize(vars.size(), 0);
  for (size_t v = 0; v < vars.size(); ++v) {
    if (!(full || s.var_changed[v])) continue;
    if (!s.estimate_moved[v]) s.estimate_moved[v] = 1, s.moved_since_chi2.push_back(static_cast<int>(v));
    vars[v] = s.lin[v];
    if (s.pos[v] >= 0) vars[v].retract(fx.dx.data() + s.pos[v]);
  }
}

}  // namespace sextant::graph::smoother
