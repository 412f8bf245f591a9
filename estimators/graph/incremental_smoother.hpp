#pragma once
// Incremental smoothing: a factor graph that grows one update at a time, whose Gauss-Newton normal equations
// H dx = -g are kept factorized (H = L D L') and modified in place instead of being refactorized — the iSAM family
// (Kaess, Ranganathan and Dellaert, "iSAM: Incremental Smoothing and Mapping", T-RO 2008; fluid relinearization as in
// iSAM2, Kaess et al., IJRR 2012), written on CHOLMOD's sparse rank-k update/downdate of an LDL' factor
// (Davis and Hager, "Multiple-rank modifications of a sparse Cholesky factorization", SIMAX 2001).
//
// The linear system is built at per-variable linearization points x0 (`linearization_point`); the estimate is
// x = x0 (+) dx.  Every update:
//   1. new variables take columns reserved after the ordered ones (reserved columns hold an identity, so they
//      cost nothing until used; the landmarks' columns come after the reserved ones, so that new keyframes are
//      eliminated before the landmarks they see); a new factor f adds (W^1/2 J_f)' as a rank-r update of L and J_f' W e_f to g;
//      the identity of each newly used column is then removed by a downdate;
//   2. dx = -(L D L')^-1 g: the forward half y = L^-1 (-g) is carried along by the updates themselves
//      (cholmod_updown_solve); the back-substitution L' dx = D^-1 y recomputes only the columns the updates modified
//      and those that depend on a step that moved by more than `wildfire` (iSAM2's wildfire, at column granularity);
//   3. fluid relinearization: every variable whose step |dx_v| exceeds the thresholds moves its linearization point,
//      x0_v <- x0_v (+) dx_v, and each factor touching it is downdated at its old linearization and updated at the
//      new one; then dx is solved again (at most `relinearization_passes` rounds per update).  A round takes the
//      variables furthest past the thresholds first, within `relinearize_work` (the entries the rank updates touch
//      along each factor's path to the root); the others wait for the next updates, their steps still in dx.
// When one round would change more factors than rank updates do cheaply (`update_fraction`), or when the reserved
// columns run out, the system is rebuilt (in a large system, spread over the next updates as a reordering is, see
// below): a fresh block ordering (constrained AMD with the newest poses and then the
// landmarks last, or METIS nested dissection above `nested_dissection_above` variables, landmarks moved last), then Gauss-Newton iterations, each
// relinearizing every factor at the current estimate and factorizing numerically (simplicial LDL', the form the
// updates need), until no variable moves past the thresholds (or the owner's `interrupt` flag is set: the rebuild
// ends after the iteration under way, counted in interrupted_rebuilds()).
//
// Reordering in the background of the updates (systems of more than `reorder_spread_above` variables, or whose L has
// more than `reorder_spread_nonzeros` entries, or of more than `reorder_spread_factors` factors): when the factor has
// filled in, or a relinearization round is too large for rank updates, the new ordering and factorization
// (relinearized at the current estimates) are built a slice at a time at the end of the next `reorder_spread` updates
// and replace the current system at a fixed update, so the estimates do not depend on the clock
// (smoother/reorder_scheduler.hpp); new variables and factors enter by rank updates meanwhile, and relinearization
// goes on within its work budget, or, when the reordering was begun for relinearization, waits for it (the new
// system brings every factor's linearization at the estimates of the update that began it).
//
// The steps, one file each under estimators/graph/smoother/: admission.hpp (which variables and factors enter, the
// gauge), rank_update.hpp (rank updates and storage packing), linear_system.hpp (ordering, assembly, sliced
// factorization, installation), back_substitution.hpp (wildfire), relinearization.hpp, reorder_scheduler.hpp (the only
// code that reads a clock), marginal_covariance.hpp; cholmod_handles.hpp owns CHOLMOD's objects.
//
// Units: a variable's step is compared component-wise: translation components (metres, point coordinates) against
// `relinearize_translation`, rotation components (radians) against `relinearize_rotation`.
// Errors: bad input (NaN values, non-positive-definite information, a factor naming an unknown variable, options out
// of range) throws std::invalid_argument with the variable, factor or option named.  Nothing else throws: a
// numerically singular system (a variable no factor determines) and a failure of CHOLMOD come back from update() and
// rebuild() as a failed status (IncrementalStatus::failure); after a CHOLMOD failure the next update() or rebuild()
// builds the factorization afresh from the graph.
#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/incremental_options.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace sextant::graph {

namespace smoother {
struct SmootherState;
}

class IncrementalSmoother {
 public:
  /// Throws std::invalid_argument naming the option when invalid_option(options) is not empty.
  explicit IncrementalSmoother(IncrementalOptions options = {});
  ~IncrementalSmoother();
  IncrementalSmoother(const IncrementalSmoother&) = delete;
  IncrementalSmoother& operator=(const IncrementalSmoother&) = delete;

  /// Adds a variable with its initial estimate (fixed variables are constants: the gauge).  Returns its index.
  /// Throws std::invalid_argument for a duplicate id or a non-finite value.
  int add_variable(const Variable& v);
  /// Adds a factor over existing variables (indices from add_variable).  Throws std::invalid_argument when it names
  /// an unknown variable or its information is not finite, symmetric and positive definite.  `robust`: the
  /// options' kernel applies to it (e.g. loop closures robust, odometry not), with `kernel_width` when given (a
  /// factor's own width, e.g. a chi-square quantile of its residual's dimension, in the units of e' Omega e) or the
  /// options' kernel_width; a width that is not positive and finite throws std::invalid_argument.
  void add_factor(std::unique_ptr<Factor> factor, bool robust = true, std::optional<double> kernel_width = {});
  /// Brings the new variables and factors into the solution and relinearizes (see the file comment).  A failed
  /// status leaves the estimates of the last good update.
  IncrementalStatus update();
  /// Relinearizes everything at the current estimate, reorders and refactorizes; then solves.
  IncrementalStatus rebuild();
  /// For a smoother not yet factorized (one built whole at once, e.g. a thinned copy of another, whose estimates are
  /// already a solution): begins its first factorization, of everything added so far, at the current estimates, as a
  /// rebuild spread over the next options().reorder_spread updates instead of within the first one.  Until the one
  /// that puts it in place, update() only works on it (status `building`): nothing is solved, the estimates stay,
  /// new variables and factors wait and enter in that update.  False (nothing begun) when the smoother is factorized
  /// already or reorder_spread is 0; the next update() then rebuilds as usual.
  /// `like`: a smoother of a system like this one (the graph this one thins), whose last reordering's pace sizes this
  /// build's slices (ReorderScheduler::pace_like).
  bool begin_spread_build(const IncrementalSmoother* like = nullptr);

  /// Recomputes every variable's step from the current factorization: update() leaves steps that would change by
  /// less than options().wildfire stale (as iSAM2's calculateEstimate), this is the exact solution of the current
  /// linearization (iSAM2's calculateBestEstimate).  One full triangular solve.
  void refresh_estimate();
  /// Current estimates (x0 (+) dx) and every factor, in insertion order.
  const FactorGraph& graph() const;
  const std::vector<Variable>& linearization_point() const;
  int index_of(int64_t id) const { return graph().index_of(id); }
  /// g2o's chi2 of the current estimate: sum of e' Omega e over all factors (pending ones included).  Each factor's
  /// term is cached and recomputed only when a solve moved one of its variables, so a call costs what changed since
  /// the last one (plus one addition per factor).
  double chi2() const;
  /// Marginal covariance of variable `index` in its tangent space (the block of H^-1 of the current factorization,
  /// from a forward solve along its path to the root of the elimination tree: cheap for recent variables);
  /// empty for a fixed or not yet determined variable.
  Eigen::MatrixXd marginal_covariance(int index) const;
  /// The robust weight of factor `index` at its linearization point (1 without a kernel): a loop closure whose
  /// weight DCS has driven near 0 has been switched off.
  double robust_weight_of(size_t index) const;

  /// Scalar unknowns in the factorized system, the nonzeros of L, and how many rebuilds happened.
  int dimension() const;
  size_t factor_nonzeros() const;
  int rebuilds() const;
  /// Rebuilds that ended at IncrementalOptions::interrupt before they converged.
  int64_t interrupted_rebuilds() const;
  /// True while a spread reordering (or a spread first factorization) is being built.
  bool reordering() const;
  /// True when variable `index` is in the factorized system (false: fixed, or added since the last update).
  bool in_system(int index) const;
  /// True when there is a factorization to solve with: false before the first update and while a spread first build
  /// (begin_spread_build) is under way.
  bool factorized() const;
  const IncrementalOptions& options() const;

 private:
  IncrementalStatus rebuild_with(int iterations);
  std::unique_ptr<smoother::SmootherState> state_;
};

}  // namespace sextant::graph
