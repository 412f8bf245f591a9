#include "estimators/graph/smoother/linear_system.hpp"

#include "estimators/graph/block_ordering.hpp"
#include "estimators/graph/smoother/back_substitution.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <algorithm>
#include <stdexcept>

namespace sextant::graph::smoother {

namespace {

// Positions for the free variables marked in `in`: a fill-reducing ordering of the block graph.  False when CHOLMOD
// fails (sys.error says so).
bool order_blocks(SmootherState& s, const std::vector<char>& in, System& sys) {
  const auto& vars = s.graph.variables();
  // Blocks: the free variables in the system, in insertion order; the newest ones are constrained to come last.
  std::vector<int> block_var, var_block(vars.size(), -1);
  for (size_t v = 0; v < in.size(); ++v)
    if (in[v] && !vars[v].fixed)
      var_block[v] = static_cast<int>(block_var.size()), block_var.push_back(static_cast<int>(v));
  const size_t nb = block_var.size();
  std::vector<std::vector<int>> upper(nb);
  for (size_t b = 0; b < nb; ++b) upper[b].push_back(static_cast<int>(b));
  for (size_t f : sys.factors)
    for (int u : s.graph.factors()[f]->variables())
      for (int w : s.graph.factors()[f]->variables()) {
        const int bu = var_block[static_cast<size_t>(u)], bw = var_block[static_cast<size_t>(w)];
        if (bu >= 0 && bw >= 0 && bu < bw) upper[static_cast<size_t>(bw)].push_back(bu);
      }
  for (auto& r : upper) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  // Hubs: landmarks (point variables), which a landmark-heavy map ties to most keyframes.  They are ordered last and
  // placed after the reserved columns, so that the keyframes added until the next ordering take columns before them.
  // Had the new keyframes come after the landmarks, every landmark's column would gain the rows of every new keyframe
  // that sees it (fill along the chain), and each sighting's rank update would walk all those columns: on a 3-D run
  // with 40 landmarks in view that cost grew with every keyframe since the last ordering.  Before them, a sighting's
  // update walks the new keyframe's column and the landmarks' dense block only.
  std::vector<char> hub(nb, 0);
  for (size_t b = 0; b < nb; ++b) hub[b] = vars[static_cast<size_t>(block_var[b])].is_point();
  std::vector<int> order;
  try {
    if (static_cast<int>(nb) > s.options.nested_dissection_above) {
      order = block_nested_dissection_order(upper, *s.workspace);
      std::stable_partition(order.begin(), order.end(), [&](int b) { return !hub[static_cast<size_t>(b)]; });
    } else {
      size_t poses = 0;
      for (size_t b = 0; b < nb; ++b) poses += hub[b] ? 0 : 1;
      const size_t newest = std::min<size_t>(poses / 10, 100);
      std::vector<int> group(nb, 0);
      for (size_t b = nb, seen = 0; b-- > 0 && seen < newest;)
        if (!hub[b]) group[b] = 1, ++seen;
      bool any_hub = false;
      for (size_t b = 0; b < nb; ++b)
        if (hub[b]) group[b] = 2, any_hub = true;
      order = block_amd_order(upper, *s.workspace, newest > 0 || any_hub ? &group : nullptr);
    }
  } catch (const std::runtime_error& e) {  // block_ordering.hpp reports CHOLMOD's failures so
    sys.error = e.what();
    return false;
  }
  sys.pos.assign(vars.size(), -1);
  sys.used = 0;
  int hub_dim = 0;
  for (int b : order) {
    const size_t v = static_cast<size_t>(block_var[static_cast<size_t>(b)]);
    if (hub[static_cast<size_t>(b)]) {
      hub_dim += vars[v].dim();
      continue;
    }
    sys.pos[v] = sys.used;
    sys.used += vars[v].dim();
  }
  sys.reserve_end = sys.used + std::max(64, static_cast<int>(s.options.capacity_growth * (sys.used + hub_dim)));
  sys.capacity = sys.reserve_end;
  for (int b : order) {
    const size_t v = static_cast<size_t>(block_var[static_cast<size_t>(b)]);
    if (!hub[static_cast<size_t>(b)]) continue;
    sys.pos[v] = sys.capacity;
    sys.capacity += vars[v].dim();
  }
  sys.col_var.assign(static_cast<size_t>(sys.capacity), -1);
  for (size_t v = 0; v < sys.pos.size(); ++v)
    for (int k = 0; sys.pos[v] >= 0 && k < vars[v].dim(); ++k)
      sys.col_var[static_cast<size_t>(sys.pos[v] + k)] = static_cast<int>(v);
  return true;
}

}  // namespace

std::unique_ptr<System> begin_system(SmootherState& s, const std::vector<char>& in, bool keep_ordering) {
  auto sys = std::make_unique<System>();
  sys->lin = s.graph.variables();
  for (size_t f = 0; f < s.weight.size(); ++f)
    if (s.weight[f] > 0) sys->factors.push_back(f);
  bool ok = true;
  if (keep_ordering) {
    sys->pos = s.pos, sys->col_var = s.fx.col_var, sys->used = s.fx.used, sys->reserve_end = s.fx.reserve_end,
    sys->capacity = s.fx.capacity;
  } else {
    ok = order_blocks(s, in, *sys);
  }
  if (ok && !assemble_pattern(s, *sys)) sys->error = "CHOLMOD could not allocate the normal equations", ok = false;
  if (!ok) {
    sys->done = true;
    sys->failure = SmootherFailure::kFactorization;
    s.workspace->status = CHOLMOD_OK;
  }
  return sys;
}

// Factors that entered the current system after `sys` was begun are not in `sys`: they, and the variables that
// entered with them, become pending again and enter `sys` by rank updates in the update that installed it (their
// variables' linearization point is their current estimate).
bool install(SmootherState& s, System& sys) {
  const size_t nv = s.graph.variables().size();
  std::vector<char> in_s(s.graph.factors().size(), 0);
  for (size_t f : sys.factors) in_s[f] = 1;
  std::vector<size_t> later_factors;
  for (size_t f = 0; f < s.weight.size(); ++f)
    if (s.weight[f] > 0 && !in_s[f]) later_factors.push_back(f), s.weight[f] = 0.0;
  if (!later_factors.empty()) {
    later_factors.insert(later_factors.end(), s.pending_factors.begin(), s.pending_factors.end());
    std::sort(later_factors.begin(), later_factors.end());
    s.pending_factors = std::move(later_factors);
  }
  std::vector<int> later_vars;
  for (size_t v = 0; v < nv; ++v) {
    const bool in_new = v < sys.pos.size() && sys.pos[v] >= 0;
    if (in_new) {
      s.lin[v] = sys.lin[v];
    } else if (s.pos[v] >= 0) {
      later_vars.push_back(static_cast<int>(v));
      s.lin[v] = s.graph.variables()[v];
    }
  }
  if (!later_vars.empty()) {
    later_vars.insert(later_vars.end(), s.pending_vars.begin(), s.pending_vars.end());
    std::sort(later_vars.begin(), later_vars.end());
    s.pending_vars = std::move(later_vars);
  }
  Factorization& fx = s.fx;
  s.pos = sys.pos;
  s.pos.resize(nv, -1);
  fx.col_var = std::move(sys.col_var);
  fx.used = sys.used;
  fx.reserve_end = sys.reserve_end;
  fx.capacity = sys.capacity;
  for (auto& fs : s.var_factors) fs.clear();
  for (size_t f : sys.factors)
    for (int v : s.graph.factors()[f]->variables()) s.var_factors[static_cast<size_t>(v)].push_back(f);
  s.factors_in_system = sys.factors.size();

  // A spread reordering replaces a factor that grew since its ordering; the new one is packed, and would grow
  // again at the next updates into fresh pages (on city10000, 30-65 ms of page faults per growth).  So it takes the
  // old one's storage size at once, while that memory has just been freed.  (A synchronous rebuild has freed the old
  // factor before building the new one, which then reuses its memory: nothing to do.)
  const size_t storage = fx.L ? fx.L->nzmax : 0;
  fx.L.reset();
  fx.y.reset();
  fx.delta_b.reset();
  fx.L = std::move(sys.L);
  if (storage > fx.L->nzmax && !cholmod_reallocate_factor(storage, fx.L.get(), s.workspace.get())) {
    s.cholmod_failure = "CHOLMOD could not grow the factor (status " + std::to_string(s.workspace->status) + ")";
    return false;
  }
  fx.y = std::move(sys.y);
  fx.g = std::move(sys.g);
  fx.delta_b = own(cholmod_zeros(static_cast<size_t>(fx.capacity), 1, CHOLMOD_REAL, s.workspace.get()), s.workspace);
  if (fx.delta_b == nullptr) {
    s.cholmod_failure = "CHOLMOD could not allocate the update's right-hand side";
    return false;
  }
  const size_t capacity = static_cast<size_t>(fx.capacity);
  fx.dx = Eigen::VectorXd::Zero(fx.capacity);
  fx.dirty.assign(capacity, 0);
  fx.seen.assign(capacity, 0.0);
  fx.recomputed.assign(capacity, 0);
  fx.on_path.assign(capacity, 0);
  fx.changed.assign(capacity, 0);
  fx.ordered_nnz = fx.nonzeros();
  fx.reserve_at_order = fx.reserve_end - fx.used;
  back_substitute(s, true);
  return true;
}

void drop_factorization(SmootherState& s) {
  s.reorder.cancel();
  s.fx.L.reset();
  s.fx.y.reset();
  s.fx.delta_b.reset();
  // What the failed update had begun to admit goes back to pending, as if it had not begun (a rebuild takes it).
  for (int v : s.pending_vars) s.pos[static_cast<size_t>(v)] = -1;
  for (size_t f : s.pending_factors) s.weight[f] = 0.0;
  s.workspace->status = CHOLMOD_OK;
}

}  // namespace sextant::graph::smoother
