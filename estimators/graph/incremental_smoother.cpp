#include "estimators/graph/incremental_smoother.hpp"

#include "estimators/graph/optimizer.hpp"
#include "estimators/graph/smoother/admission.hpp"
#include "estimators/graph/smoother/back_substitution.hpp"
#include "estimators/graph/smoother/linear_system.hpp"
#include "estimators/graph/smoother/marginal_covariance.hpp"
#include "estimators/graph/smoother/rank_update.hpp"
#include "estimators/graph/smoother/relinearization.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace sextant::graph {

using smoother::SmootherState;

namespace {

const IncrementalOptions& checked(const IncrementalOptions& o) {
  if (auto why = invalid_option(o); !why.empty()) throw std::invalid_argument("incremental smoother: " + why);
  return o;
}

// An update that ended in a rebuild reports what it admitted itself (the rebuild finds nothing pending).
IncrementalStatus with_admission(IncrementalStatus r, const IncrementalStatus& st) {
  r.new_variables = st.new_variables, r.new_factors = st.new_factors, r.deferred_variables = st.deferred_variables;
  return r;
}

// The owner asked a long computation to end (IncrementalOptions::interrupt).
bool interrupted(const IncrementalOptions& o) { return o.interrupt && o.interrupt->load(std::memory_order_relaxed); }

// A CHOLMOD failure in the middle of an update: the factorization is dropped, the next update rebuilds it.
IncrementalStatus cholmod_failed(SmootherState& s, IncrementalStatus st) {
  smoother::drop_factorization(s);
  st.ok = false;
  st.failure = SmootherFailure::kFactorization;
  st.message = s.cholmod_failure + "; the next update rebuilds the factorization";
  return st;
}

// An update during a spread first build: nothing solved, everything new waits.
IncrementalStatus building(const SmootherState& s) {
  IncrementalStatus st;
  st.building = true;
  st.deferred_variables = static_cast<int>(s.pending_vars.size());
  return st;
}

// Rebuilds (reorderings, relinearization of everything) are spread over updates in a system this large.
bool spreads_rebuilds(const SmootherState& s) {
  const IncrementalOptions& o = s.options;
  return o.reorder_spread > 0 && (static_cast<int>(s.graph.variables().size()) > o.reorder_spread_above ||
                                  s.fx.nonzeros() > static_cast<size_t>(o.reorder_spread_nonzeros) ||
                                  s.factors_in_system > static_cast<size_t>(o.reorder_spread_factors));
}

}  // namespace

IncrementalSmoother::IncrementalSmoother(IncrementalOptions options)
    : state_(std::make_unique<SmootherState>(checked(options))) {}

IncrementalSmoother::~IncrementalSmoother() = default;

int IncrementalSmoother::add_variable(const Variable& v) {
  SmootherState& s = *state_;
  if (!v.finite()) throw std::invalid_argument("variable " + std::to_string(v.id) + " has a NaN or infinite value");
  const int i = s.graph.add_variable(v);  // throws for a duplicate id
  s.lin.push_back(v);
  s.pos.push_back(-1);
  s.var_factors.emplace_back();
  s.pending_vars.push_back(i);
  return i;
}

void IncrementalSmoother::add_factor(std::unique_ptr<Factor> factor, bool robust, std::optional<double> kernel_width) {
  SmootherState& s = *state_;
  const size_t index = s.graph.factors().size();
  if (auto why = validate_factor(s.graph.variables(), *factor, index); !why.empty()) throw std::invalid_argument(why);
  if (kernel_width && !(std::isfinite(*kernel_width) && *kernel_width > 0))
    throw std::invalid_argument("factor " + std::to_string(index) + ": kernel width " + std::to_string(*kernel_width) +
                                " is not a positive finite number");
  s.pending_factors.push_back(index);
  s.weight.push_back(0.0);
  s.kernel_width.push_back(robust ? kernel_width.value_or(s.options.kernel_width) : 0.0);
  s.graph.add_factor(std::move(factor));
}

IncrementalStatus IncrementalSmoother::update() {
  SmootherState& s = *state_;
  s.reorder.update_begins();
  ++s.update_calls;
  if (s.update_calls == s.options.fail_factorization_at_update) s.workspace.arm_fault();
  smoother::hold_gauge(s);
  if (s.fx.L == nullptr && !s.reorder.under_way()) return rebuild();
  IncrementalStatus st;
  if (s.fx.L == nullptr && smoother::first_build_slice(s)) return building(s);  // a spread first build, not yet due
  if (s.reorder.due(s.update_calls)) {
    switch (s.reorder.finish(s)) {
      case smoother::ReorderScheduler::Finished::kInstalled:
        st.rebuilt = true, ++st.solves;
        break;
      case smoother::ReorderScheduler::Finished::kFailed:
        return rebuild_with(1);  // which names the cause
      case smoother::ReorderScheduler::Finished::kCholmodFailed:
        return cholmod_failed(s, st);
    }
  }

  // 1. Admission: the pending variables their factors determine, and the factors all of whose variables are in.
  const smoother::Admission admitted = smoother::admit(s);
  if (admitted.factors_in.size() > smoother::update_limit(s))
    return rebuild();  // a batch: iterate as a batch solve would
  if (s.fx.used + admitted.new_dim > s.fx.reserve_end) return rebuild_with(1);  // only room is needed
  st.new_variables = static_cast<int>(admitted.vars_in.size());
  st.new_factors = static_cast<int>(admitted.factors_in.size());
  st.deferred_variables = static_cast<int>(admitted.vars_wait.size());

  // 2. Rank updates bring them into the factor.
  bool definite = true;
  if (!smoother::enter_by_rank_updates(s, admitted, definite)) return cholmod_failed(s, st);
  if (!definite || s.workspace->status == CHOLMOD_NOT_POSDEF) {
    s.workspace->status = CHOLMOD_OK;
    return with_admission(rebuild(), st);
  }

  // 3. Fill-in: reorder now (small systems) or begin a reordering spread over the next updates.
  const bool filled =
      static_cast<double>(s.fx.nonzeros()) > s.options.refill_ratio * static_cast<double>(s.fx.ordered_nnz);
  const bool spread = spreads_rebuilds(s);
  if (filled && !spread) return with_admission(rebuild_with(1), st);  // the new ordering is the point: one iteration
  bool began_reordering =
      !s.reorder.under_way() && spread && (filled || 4 * (s.fx.reserve_end - s.fx.used) < s.fx.reserve_at_order);
  if (began_reordering) s.reorder.begin(s);

  // 4. Back-substitution, then fluid relinearization and a new solve, a few rounds.
  smoother::back_substitute(s, false);
  ++st.solves;
  ++s.updates;
  const bool check = s.options.relinearize_skip <= 1 || s.updates % s.options.relinearize_skip == 0;
  // Not while a reordering begun for relinearization is under way (ReorderScheduler::relinearizing says why); while
  // one begun for fill-in is, within the work budget until it lands.
  for (int pass = 0; check && !s.reorder.relinearizing() && pass < s.options.relinearization_passes; ++pass) {
    const std::vector<int> moved = smoother::moved_variables(s);
    if (moved.empty()) break;
    switch (smoother::relinearize(s, moved, st, !(spread && s.reorder.under_way()))) {
      case smoother::Relinearized::kDone:
        break;
      // Relinearizing everything at the estimate is the point: one iteration, now (small systems) or spread over
      // the next updates as a reordering is (the current factor stays exact meanwhile, only linearized further away).
      case smoother::Relinearized::kTooMany:
        if (!spread) return with_admission(rebuild_with(1), st);
        s.reorder.begin(s, true);
        began_reordering = true;
        continue;
      case smoother::Relinearized::kCholmodFailed:
        return cholmod_failed(s, st);
    }
    smoother::back_substitute(s, false);
    ++st.solves;
  }

  // 5. This update's slice of a reordering under way.
  s.reorder.work(s, began_reordering);
  return st;
}

IncrementalStatus IncrementalSmoother::rebuild() { return rebuild_with(state_->options.rebuild_iterations); }

bool IncrementalSmoother::begin_spread_build(const IncrementalSmoother* like) {
  SmootherState& s = *state_;
  if (s.fx.L != nullptr || s.reorder.under_way() || s.options.reorder_spread <= 0) return false;
  if (like != nullptr) s.reorder.pace_like(like->state_->reorder);
  s.reorder.request_first_build();  // begun by the next update: the caller has just built the whole graph
  return true;
}

IncrementalStatus IncrementalSmoother::rebuild_with(int iterations) {
  SmootherState& s = *state_;
  IncrementalStatus st;
  st.rebuilt = true;
  s.reorder.cancel();  // superseded
  const std::vector<int> pending_vars = s.pending_vars;
  const std::vector<size_t> pending_factors = s.pending_factors;
  // Everything in the system relinearized at the current estimate (begin_system), with what enters now.
  const std::vector<char> in = smoother::admit_for_rebuild(s, st);

  ++s.rebuilds;
  for (int it = 0; it < std::max(1, iterations); ++it) {
    if (it > 0 && interrupted(s.options)) {  // the last iteration's factorization is installed: consistent
      st.interrupted = true;
      ++s.interrupted_rebuilds;
      break;
    }
    if (it > 0 && smoother::moved_variables(s).empty()) break;
    // The old factor goes first: the new one then reuses its memory instead of faulting in fresh pages (M3500: peak
    // RSS 34.4 MB with both alive, 30.5 before).
    s.fx.L.reset();
    s.fx.y.reset();
    // Every factor in the system linearized at the current estimate; the first iteration orders, the others keep it.
    std::unique_ptr<smoother::System> sys = smoother::begin_system(s, in, it > 0);
    smoother::advance(s, *sys, {});
    if (!sys->error.empty()) {  // the factor is gone: the next update starts over
      st.ok = false;
      st.failure = sys->failure;
      st.message = sys->error;
      if (sys->failure == SmootherFailure::kFactorization) {
        // What this rebuild admitted waits again, so that the next one takes it as if this one had not run.
        s.pending_vars = pending_vars;
        s.pending_factors = pending_factors;
        smoother::drop_factorization(s);
      }
      return st;
    }
    if (!smoother::install(s, *sys)) return cholmod_failed(s, st);
    ++st.solves;
  }
  return st;
}

void IncrementalSmoother::refresh_estimate() { smoother::back_substitute(*state_, true); }

const FactorGraph& IncrementalSmoother::graph() const { return state_->graph; }
const std::vector<Variable>& IncrementalSmoother::linearization_point() const { return state_->lin; }
int IncrementalSmoother::dimension() const { return state_->fx.used + state_->fx.capacity - state_->fx.reserve_end; }
size_t IncrementalSmoother::factor_nonzeros() const { return state_->fx.nonzeros(); }
int IncrementalSmoother::rebuilds() const { return state_->rebuilds; }
int64_t IncrementalSmoother::interrupted_rebuilds() const { return state_->interrupted_rebuilds; }
bool IncrementalSmoother::reordering() const { return state_->reorder.under_way(); }
bool IncrementalSmoother::factorized() const { return state_->fx.L != nullptr; }
bool IncrementalSmoother::in_system(int index) const {
  return index >= 0 && static_cast<size_t>(index) < state_->pos.size() && state_->pos[static_cast<size_t>(index)] >= 0;
}
const IncrementalOptions& IncrementalSmoother::options() const { return state_->options; }

double IncrementalSmoother::chi2() const {
  // Each factor's e' Omega e is kept from the last call and recomputed only for the factors of the variables whose
  // estimate a solve moved since then (and for new or pending ones): the cost follows what the updates touched.
  SmootherState& s = *state_;
  const auto& factors = s.graph.factors();
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  s.factor_chi2.resize(factors.size(), unknown);
  for (int v : s.moved_since_chi2) {
    s.estimate_moved[static_cast<size_t>(v)] = 0;
    for (size_t f : s.var_factors[static_cast<size_t>(v)]) s.factor_chi2[f] = unknown;
  }
  s.moved_since_chi2.clear();
  for (size_t f : s.pending_factors) s.factor_chi2[f] = unknown;
  double sum = 0;
  Eigen::VectorXd e, weighted;  // scratch, reused across factors
  for (size_t f = 0; f < factors.size(); ++f) {
    if (std::isnan(s.factor_chi2[f])) s.factor_chi2[f] = factors[f]->chi2(s.graph.variables(), e, weighted);
    sum += s.factor_chi2[f];
  }
  return sum;
}

double IncrementalSmoother::robust_weight_of(size_t fi) const {
  const SmootherState& s = *state_;
  if (s.kernel_width[fi] == 0) return 1.0;
  const Factor& f = *s.graph.factors()[fi];
  Eigen::VectorXd e, weighted;
  return s.kernel_weight(fi, f.chi2(s.lin, e, weighted));
}

Eigen::MatrixXd IncrementalSmoother::marginal_covariance(int index) const {
  return smoother::marginal_covariance(*state_, index);
}

}  // namespace sextant::graph
