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

namespace {

// Rank-update work of a modification starting at column j: CHOLMOD's rank update walks the path from j to the root
// of the elimination tree and touches every entry of each column on it, so the work is the sum of the column counts
// along the path.  Memoized per column in `memo` (-1: not yet), as paths share their upper parts.
double path_work(const Factorization& fx, int j, std::vector<double>& memo) {
  const int* Lnz = static_cast<const int*>(fx.L->nz);
  std::vector<int> walk;
  for (int c = j; c >= 0 && memo[static_cast<size_t>(c)] < 0; c = fx.parent_of(c)) walk.push_back(c);
  for (size_t k = walk.size(); k-- > 0;) {
    const int c = walk[k], parent = fx.parent_of(c);
    memo[static_cast<size_t>(c)] = Lnz[c] + (parent >= 0 ? memo[static_cast<size_t>(parent)] : 0.0);
  }
  return memo[static_cast<size_t>(j)];
}

// How far past its thresholds variable v's step is (the largest ratio over its components).
double urgency(const SmootherState& s, int v) {
  const Variable& x = s.lin[static_cast<size_t>(v)];
  double most = 0;
  for (int i = 0; i < x.dim(); ++i) {
    const double limit =
        is_rotation_component(x.kind, i) ? s.options.relinearize_rotation : s.options.relinearize_translation;
    most = std::max(most, std::abs(s.fx.dx[s.pos[static_cast<size_t>(v)] + i]) / limit);
  }
  return most;
}

}  // namespace

std::vector<int> within_work_budget(const SmootherState& s, std::vector<int> moved, std::vector<size_t>& factors,
                                    bool* too_heavy) {
  std::vector<double> how_far(s.lin.size(), 0.0);
  for (int v : moved) how_far[static_cast<size_t>(v)] = urgency(s, v);
  std::stable_sort(moved.begin(), moved.end(),
                   [&](int a, int b) { return how_far[static_cast<size_t>(a)] > how_far[static_cast<size_t>(b)]; });
  std::vector<double> memo(static_cast<size_t>(s.fx.capacity), -1.0);
  std::vector<char> mark(s.graph.factors().size(), 0);
  std::vector<int> chosen;
  double work = 0;
  const size_t limit = update_limit(s);
  for (int v : moved) {
    double own = 0;
    std::vector<size_t> fresh;
    for (size_t f : s.var_factors[static_cast<size_t>(v)]) {
      if (mark[f]) continue;
      int first = s.fx.capacity;
      for (int u : s.graph.factors()[f]->variables())
        if (s.pos[static_cast<size_t>(u)] >= 0) first = std::min(first, s.pos[static_cast<size_t>(u)]);
      own += s.graph.factors()[f]->residual_dim() * path_work(s.fx, first, memo);
      fresh.push_back(f);
    }
    if (fresh.size() > kHubFactors && own > kHubRebuildAbove * s.options.relinearize_work) {
      if (too_heavy) *too_heavy = true;
      continue;  // a rebuild relinearizes it (the caller's choice), or the reordering under way will
    }
    if (chosen.empty() && own > s.options.relinearize_work && s.updates % s.options.heavy_relinearize_every != 0)
      continue;  // alone over the budget: waits for the next update whose turn it is (heavy_relinearize_every)
    if (!chosen.empty() && (work + own > s.options.relinearize_work || factors.size() + fresh.size() > limit))
      continue;  // waits for a later update
    work += own;
    chosen.push_back(v);
    for (size_t f : fresh) mark[f] = 1, factors.push_back(f);
  }
  return chosen;
}

Relinearized relinearize(SmootherState& s, const std::vector<int>& all_moved, IncrementalStatus& st,
                         bool rebuild_if_many) {
  // Rank updates cost about the path of each factor's columns to the root of the elimination tree; past a few
  // dozen factors a rebuild is cheaper (measured on M3500: bench/RESULTS.md), and the caller rebuilds instead.
  // Below that, the most-moved variables are relinearized within relinearize_work and the others at the next
  // updates (their steps stay in the solution meanwhile, at their old linearization point): on 3-D graphs, whose
  // paths are long and dense, no update pays for a whole correction at once.
  if (rebuild_if_many) {
    std::vector<char> mark(s.graph.factors().size(), 0);
    size_t touching = 0;
    for (int v : all_moved)
      for (size_t f : s.var_factors[static_cast<size_t>(v)]) touching += mark[f] ? 0 : 1, mark[f] = 1;
    if (touching > update_limit(s)) return Relinearized::kTooMany;
  }
  std::vector<size_t> factors;
  bool too_heavy = false;
  const std::vector<int> moved = within_work_budget(s, all_moved, factors, &too_heavy);
  if (too_heavy && rebuild_if_many) return Relinearized::kTooMany;
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
