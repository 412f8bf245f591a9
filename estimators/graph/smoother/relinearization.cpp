#include "estimators/graph/smoother/relinearization.hpp"

#include "estimators/graph/smoother/rank_update.hpp"

#include <algorithm>
#include <cmath>

namespace sextant::graph::smoother {

std::vector<int> moved_variables(const SmootherState& s) {
  std::vector<int> moved;
  const auto& vars = s.lin;
  for (size_t v = 0; v < vars.size(); ++v) {
    const int p = s.pos[v];
    if (p < 0) continue;
    for (int i = 0; i < vars[v].dim(); ++i) {
      const double step = std::abs(s.fx.dx[p + i]);
      const double limit =
          is_rotation_component(vars[v].kind, i) ? s.options.relinearize_rotation : s.options.relinearize_translation;
      if (step > limit) {
        moved.push_back(static_cast<int>(v));
        break;
      }
    }
  }
  return moved;
}

size_t update_limit(const SmootherState& s) {
  const IncrementalOptions& o = s.options;
  const size_t fraction = std::max(static_cast<size_t>(o.min_update_factors),
                                   static_cast<size_t>(o.update_fraction * static_cast<double>(s.factors_in_system)));
  return std::min(fraction, static_cast<size_t>(std::max(o.max_update_factors, o.min_update_factors)));
}

Relinearized relinearize(SmootherState& s, const std::vector<int>& moved, IncrementalStatus& st) {
  // Rank updates cost about the path of each factor's columns to the root of the elimination tree; past a few
  // dozen factors a rebuild is cheaper (measured on M3500: bench/RESULTS.md), and the caller rebuilds instead.
  std::vector<char> mark(s.graph.factors().size(), 0);
  std::vector<size_t> factors;
  for (int v : moved)
    for (size_t f : s.var_factors[static_cast<size_t>(v)])
      if (!mark[f]) mark[f] = 1, factors.push_back(f);
  if (factors.size() > update_limit(s)) return Relinearized::kTooMany;
  std::vector<Contribution> before, after;
  before.reserve(factors.size());
  after.reserve(factors.size());
  for (size_t f : factors) before.push_back(linearize(s, f));
  for (int v : moved) {
    const size_t vi = static_cast<size_t>(v);
    s.lin[vi].retract(s.fx.dx.data() + s.pos[vi]);
    // dx must describe the same estimate at the new linearization point: its step is now 0.
    // (Its subtree's steps depend on this number, not on the estimate it stands for, so they are recomputed.)
    for (int k = 0; k < s.lin[vi].dim(); ++k) s.fx.dx[s.pos[vi] + k] = 0.0;
  }
  for (size_t f : factors) after.push_back(linearize(s, f));
  // Update with the new linearization before downdating the old one: the matrix stays positive definite throughout.
  if (!apply(s, after, true, true) || !apply(s, before, false, true)) return Relinearized::kCholmodFailed;
  st.relinearized_variables += static_cast<int>(moved.size());
  st.relinearized_factors += static_cast<int>(factors.size());
  return Relinearized::kDone;
}

}  // namespace sextant::graph::smoother
