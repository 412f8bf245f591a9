#pragma once
// Incremental smoothing: a factor graph that grows one update at a time, whose Gauss-Newton normal equations
// H dx = -g are kept factorized (H = L D L') and modified in place instead of being refactorized — the iSAM family
// (Kaess, Ranganathan and Dellaert, "iSAM: Incremental Smoothing and Mapping", T-RO 2008; fluid relinearization as in
// iSAM2, Kaess et al., IJRR 2012), written on CHOLMOD's sparse rank-k update/downdate of an LDL' factor
// (Davis and Hager, "Multiple-rank modifications of a sparse Cholesky factorization", SIMAX 2001).
//
// The linear system is built at per-variable linearization points x0 (`linearization_point`); the estimate is
// x = x0 (+) dx.  Every update:
//   1. new variables take columns reserved at the end of the ordering (reserved columns hold an identity, so they
//      cost nothing until used); a new factor f adds (W^1/2 J_f)' as a rank-r update of L and J_f' W e_f to g;
//      the identity of each newly used column is then removed by a downdate;
//   2. dx = -(L D L')^-1 g: the forward half y = L^-1 (-g) is carried along by the updates themselves
//      (cholmod_updown_solve); the back-substitution L' dx = D^-1 y recomputes only the columns the updates modified
//      and those that depend on a step that moved by more than `wildfire` (iSAM2's wildfire, at column granularity);
//   3. fluid relinearization: every variable whose step |dx_v| exceeds the thresholds moves its linearization point,
//      x0_v <- x0_v (+) dx_v, and each factor touching it is downdated at its old linearization and updated at the
//      new one; then dx is solved again (at most `relinearization_passes` rounds per update).
// When one round would change more factors than rank updates do cheaply (`update_fraction`), or when the reserved
// columns run out, the system is rebuilt: a fresh block ordering (constrained AMD with the newest variables last, or
// METIS nested dissection above `nested_dissection_above` variables), then Gauss-Newton iterations, each
// relinearizing every factor at the current estimate and factorizing numerically (simplicial LDL', the form the
// updates need), until no variable moves past the thresholds.
//
// Reordering in the background of the updates (systems of more than `reorder_spread_above` variables).  When the
// factor has filled in past `refill_ratio` times its size after the last ordering (or the reserved columns are three
// quarters used), the current factor is still exact, only slower to update; so the new ordering and factorization are built a slice at a time at the end of the next
// `reorder_spread` updates (each spends on it what is left of `reorder_slice_ms` after its own work, and at least its
// share of the time the previous reordering took), and the new
// system replaces the old one at the start of the update `reorder_spread` after the one that began it, whatever the
// clock said: the estimates after every update are the same on a fast or a slow machine (deterministic replay), only
// the per-update latency depends on the slices.  The new system is linearized at the estimates of the update that
// began it; the factors and variables that arrived in between enter it as the pending ones of the replacing update.
// The work is CHOLMOD's row-by-row factorization (cholmod_rowfac, which can compute any range of rows whose
// descendants are done), so the slices give exactly the factor one call would.
//
// Units: a variable's step is compared component-wise: translation components (metres, point coordinates) against
// `relinearize_translation`, rotation components (radians) against `relinearize_rotation`.
// Errors: bad input (NaN values, non-positive-definite information, a factor naming an unknown variable) throws
// std::invalid_argument at insertion with the variable or factor named; a numerically singular system (a variable
// no factor determines) comes back from update() as a failed status naming the variable.
#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/robust_kernel.hpp"

#include <cholmod.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sextant::graph {

struct IncrementalOptions {
  double relinearize_translation = 0.1;   // m: relinearize a variable whose step exceeds this in a translation component
  double relinearize_rotation = 0.1;      // rad: ... or this in a rotation component
  int relinearization_passes = 2;         // relinearize + re-solve rounds per update
  int relinearize_skip = 1;               // look for variables to relinearize every this many updates (iSAM2's relinearizeSkip)
  /// Factors changed by rank updates in one round (new ones or relinearized ones) beyond which a rebuild is cheaper:
  /// max(min_update_factors, update_fraction x factors in the system), at most max_update_factors.  The cap matters on
  /// large graphs, where each factor's path to the root is long: on city10000 relinearizing 158 factors by rank
  /// updates took 80-90 ms, more than a rebuild; below 6400 factors it changes nothing (bench/RESULTS.md, session 5).
  double update_fraction = 0.02;
  int min_update_factors = 32;
  int max_update_factors = 128;
  int rebuild_iterations = 10;            // Gauss-Newton iterations of a rebuild for new factors that would cost more as
                                          // rank updates (until no variable moves past the thresholds); a rebuild for
                                          // relinearization or reordering takes one
  double refill_ratio = 1.5;              // rebuild (reorder) when nnz(L) exceeds this multiple of its size after ordering
                                          // (city10000: 1.5 takes 0.68 of the CPU time of 2.5, 1.25 0.62 with more rebuilds)
  /// Orderings at rebuilds: constrained AMD with the newest variables last up to this many variables, METIS nested
  /// dissection above (city10000: half the factorization flops; M3500: its ordering time outweighs the gain).
  int nested_dissection_above = 5000;
  double capacity_growth = 1.0;           // reserved columns at a rebuild: this fraction of the used ones (and >= 64)
  /// Updates over which a fill-triggered reordering is spread (see the file comment); 0: reorder within the update.
  int reorder_spread = 8;
  /// Spread reorderings only in systems of more than this many variables: below, a reordering takes a few ms, and
  /// holding two factors at once would cost more memory than it saves time (M3500: +5 MB peak RSS, p99 unchanged).
  int reorder_spread_above = 5000;
  /// ms: an update works on a spread reordering until this long after it began, and at least for its share of the
  /// time the last one took (1.25 x that time / reorder_spread), so that the installing update is left little.
  double reorder_slice_ms = 4.0;
  /// Wildfire threshold of the back-substitution (as iSAM2's): a change of a step by less than this (m or rad) is not
  /// propagated to the variables that depend on it (they keep a value stale by less than it).  0: exact.
  double wildfire = 1e-3;
  RobustKernel kernel = RobustKernel::kNone;
  double kernel_width = 1.0;
};

struct IncrementalStatus {
  bool ok = true;
  std::string message;               // why !ok
  int new_variables = 0, new_factors = 0;
  int deferred_variables = 0;        // new variables not yet determined by their factors (kept pending)
  int relinearized_variables = 0, relinearized_factors = 0;
  bool rebuilt = false;              // the system was reordered and refactorized in this update (or a spread
                                     // reordering was put in place)
  int solves = 0;
};

class IncrementalSmoother {
 public:
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
  /// Brings the new variables and factors into the solution and relinearizes (see the file comment).
  IncrementalStatus update();
  /// Relinearizes everything at the current estimate, reorders and refactorizes; then solves.
  IncrementalStatus rebuild();

  /// Recomputes every variable's step from the current factorization: update() leaves steps that would change by
  /// less than options().wildfire stale (as iSAM2's calculateEstimate), this is the exact solution of the current
  /// linearization (iSAM2's calculateBestEstimate).  One full triangular solve.
  void refresh_estimate() { solve(true); }
  /// Current estimates (x0 (+) dx) and every factor, in insertion order.
  const FactorGraph& graph() const { return graph_; }
  const std::vector<Variable>& linearization_point() const { return lin_; }
  int index_of(int64_t id) const { return graph_.index_of(id); }
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
  int dimension() const { return used_ + capacity_ - reserve_end_; }
  size_t factor_nonzeros() const;
  int rebuilds() const { return rebuilds_; }
  /// True while a spread reordering is being built.
  bool reordering() const { return reordering_ != nullptr; }
  const IncrementalOptions& options() const { return options_; }

 private:
  struct Contribution;  // one factor's (W^1/2 J)' and J' W e at the linearization point
  Contribution linearize(size_t factor) const;
  double kernel_weight(size_t factor, double chi2) const;  // the robust weight at e' Omega e = chi2
  struct System;  // an ordering, a linearization point and the factorization being built for them
  std::unique_ptr<System> begin_system(const std::vector<char>& in, bool keep_ordering) const;
  void assemble_pattern(System& s) const;          // H's pattern (upper, reserved columns = identity), zero values
  void assemble_values(System& s, size_t end) const;  // linearizes the system's factors up to `end` into H and g
  /// Works on `s` until `deadline` (or to the end): assembly, symbolic analysis, factorization row by row, the forward
  /// solve.  Returns true when done (s.error says whether it failed).
  template <class Deadline>
  bool advance(System& s, const Deadline& deadline);
  void install(System& s);                         // makes `s` the current system (see the file comment)
  /// Adds (or removes) the contributions by one rank-k modification of L.  `within_pattern`: C C' lies in the
  /// pattern L L' already has (a relinearized factor, a reserved column's identity), so nothing fills in and L needs
  /// no room (Davis and Hager 2001: the new pattern of a column is its old one and the rows C brings along its path).
  void apply(const std::vector<Contribution>& cs, bool add, bool within_pattern = false);
  void make_room(const cholmod_sparse* C);  // packs L before an update that could otherwise make CHOLMOD reallocate it
  void determined(const std::vector<int>& new_vars, const std::vector<size_t>& new_factors,
                  std::vector<char>& ready) const;
  /// dx from y by back-substitution: every column (`full`), or only the modified ones and those that depend on a
  /// column that moved by more than options_.wildfire; then the estimates of the variables whose step changed.
  void solve(bool full);
  int parent_of(int column) const;  // in the elimination tree of L, -1 for a root
  std::vector<int> moved_variables() const;
  bool relinearize(const std::vector<int>& moved, IncrementalStatus& st);
  IncrementalStatus rebuild_with(int iterations);
  void order_blocks(const std::vector<char>& in, System& s) const;
  void begin_reordering();  // a spread reordering of everything in the system at the current estimates
  bool finish_reordering(IncrementalStatus& st);  // puts a due reordering in place; false: it failed (rebuild)

  IncrementalOptions options_;
  FactorGraph graph_;                 // estimates and factors
  std::vector<Variable> lin_;         // linearization points
  std::vector<int> pos_;              // per variable: first column in L (the ordering), -1: fixed or not yet in
  std::vector<double> weight_;        // per factor: 1 once in the system, 0 while pending
  std::vector<double> kernel_width_;  // per factor: its robust kernel's width, 0: no kernel
  std::vector<std::vector<size_t>> var_factors_;  // per variable: the factors in the system that touch it
  std::vector<int> pending_vars_;
  std::vector<size_t> pending_factors_;
  int used_ = 0, reserve_end_ = 0, capacity_ = 0;  // as System's: variables, reserved, hubs
  size_t ordered_nnz_ = 0;
  int rebuilds_ = 0;
  size_t factors_in_system_ = 0;
  int64_t updates_ = 0;              // updates that solved incrementally (relinearize_skip counts these)
  int64_t update_calls_ = 0;         // every update(): the clock of spread reorderings
  size_t update_limit() const;
  bool gauge_checked_ = false;
  mutable cholmod_common common_{};  // CHOLMOD's settings and workspace (used by const queries too)
  cholmod_factor* L_ = nullptr;
  Eigen::VectorXd g_;                 // gradient J' W e at the linearization point, by column
  Eigen::VectorXd dx_;                // solution, by column
  cholmod_dense* y_ = nullptr;        // L^-1 (-g): the forward solve, updated with the factor
  cholmod_dense* delta_b_ = nullptr;  // scratch for cholmod_updown_solve (zero between calls)
  std::vector<char> dirty_;           // per column: modified by an update since the last solve
  std::vector<char> recomputed_;      // per column, during a solve
  std::vector<char> on_path_;         // per column, during make_room (all 0 between calls)
  std::vector<char> changed_;         // per column, during a solve: moved past the wildfire threshold
  std::vector<double> seen_;          // per column: its step when its subtree was last recomputed
  std::vector<int> col_var_;          // per column: the variable, -1 for a reserved column
  std::vector<char> var_changed_;     // per variable, after a solve: its step changed
  mutable std::vector<int> marginal_slot_;
  mutable std::vector<double> factor_chi2_;   // per factor: e' Omega e at the estimate of the last chi2() (NaN: stale)
  mutable std::vector<char> estimate_moved_;  // per variable: its estimate moved since the last chi2()
  mutable std::vector<int> moved_since_chi2_; // those variables  // per column, during marginal_covariance (all -1 between calls)
  std::unique_ptr<System> reordering_;  // a spread reordering under way
  int64_t reorder_due_ = 0;           // the update (updates_ count) at which it replaces the current system
  double reorder_spent_ms_ = 0.0;     // time its slices have taken so far
  double reorder_work_ms_ = 0.0;      // time the last spread reordering took from its first slice to its installation
  int reserve_at_order_ = 0;          // reserved columns right after the last ordering
};

}  // namespace sextant::graph
