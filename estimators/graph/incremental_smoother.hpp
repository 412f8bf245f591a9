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
//   2. dx = -(L D L')^-1 g (one sparse triangular solve pair);
//   3. fluid relinearization: every variable whose step |dx_v| exceeds the thresholds moves its linearization point,
//      x0_v <- x0_v (+) dx_v, and each factor touching it is downdated at its old linearization and updated at the
//      new one; then dx is solved again (at most `relinearization_passes` rounds per update).
// When one round would change more factors than rank updates do cheaply (`update_fraction`), when the reserved
// columns run out, or when the factor has filled in past `refill_ratio` times its size after the last ordering, the
// system is rebuilt: a fresh block-AMD ordering (newest variables last), then Gauss-Newton iterations, each
// relinearizing every factor at the current estimate and factorizing numerically (supernodal, then converted to the
// simplicial LDL' form the updates need), until no variable moves past the thresholds.
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
#include <string>
#include <vector>

namespace sextant::graph {

struct IncrementalOptions {
  double relinearize_translation = 0.1;   // m: relinearize a variable whose step exceeds this in a translation component
  double relinearize_rotation = 0.1;      // rad: ... or this in a rotation component
  int relinearization_passes = 2;         // relinearize + re-solve rounds per update
  int relinearize_skip = 1;               // look for variables to relinearize every this many updates (iSAM2's relinearizeSkip)
  /// Factors changed by rank updates in one round (new ones or relinearized ones) beyond which a rebuild is cheaper:
  /// max(min_update_factors, update_fraction x factors in the system).
  double update_fraction = 0.02;
  int min_update_factors = 32;
  int rebuild_iterations = 10;            // Gauss-Newton iterations of a rebuild for new factors that would cost more as
                                          // rank updates (until no variable moves past the thresholds); a rebuild for
                                          // relinearization or reordering takes one
  double refill_ratio = 2.5;              // rebuild (reorder) when nnz(L) exceeds this multiple of its size after ordering
  double capacity_growth = 1.0;           // reserved columns at a rebuild: this fraction of the used ones (and >= 64)
  RobustKernel kernel = RobustKernel::kNone;
  double kernel_width = 1.0;
};

struct IncrementalStatus {
  bool ok = true;
  std::string message;               // why !ok
  int new_variables = 0, new_factors = 0;
  int deferred_variables = 0;        // new variables not yet determined by their factors (kept pending)
  int relinearized_variables = 0, relinearized_factors = 0;
  bool rebuilt = false;              // the system was reordered and refactorized in this update
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
  /// options' kernel applies to it (e.g. loop closures robust, odometry not).
  void add_factor(std::unique_ptr<Factor> factor, bool robust = true);
  /// Brings the new variables and factors into the solution and relinearizes (see the file comment).
  IncrementalStatus update();
  /// Relinearizes everything at the current estimate, reorders and refactorizes; then solves.
  IncrementalStatus rebuild();

  /// Current estimates (x0 (+) dx) and every factor, in insertion order.
  const FactorGraph& graph() const { return graph_; }
  const std::vector<Variable>& linearization_point() const { return lin_; }
  int index_of(int64_t id) const { return graph_.index_of(id); }
  /// g2o's chi2 of the current estimate: sum of e' Omega e over all factors (pending ones included).
  double chi2() const { return graph_.chi2(); }
  /// Marginal covariance of variable `index` in its tangent space (the block of H^-1, one solve per component);
  /// empty for a fixed or not yet determined variable.
  Eigen::MatrixXd marginal_covariance(int index) const;
  /// The robust weight of factor `index` at its linearization point (1 without a kernel): a loop closure whose
  /// weight DCS has driven near 0 has been switched off.
  double robust_weight_of(size_t index) const;

  /// Scalar unknowns in the factorized system, the nonzeros of L, and how many rebuilds happened.
  int dimension() const { return used_; }
  size_t factor_nonzeros() const;
  int rebuilds() const { return rebuilds_; }
  const IncrementalOptions& options() const { return options_; }

 private:
  struct Contribution;  // one factor's (W^1/2 J)' and J' W e at the linearization point
  Contribution linearize(size_t factor) const;
  void apply(const Contribution& c, bool add);
  void determined(const std::vector<int>& new_vars, const std::vector<size_t>& new_factors,
                  std::vector<char>& ready) const;
  void solve();
  std::vector<int> moved_variables() const;
  bool relinearize(const std::vector<int>& moved, IncrementalStatus& st);
  std::string factorize_all();
  IncrementalStatus rebuild_with(int iterations);

  IncrementalOptions options_;
  FactorGraph graph_;                 // estimates and factors
  std::vector<Variable> lin_;         // linearization points
  std::vector<int> pos_;              // per variable: first column in L (the ordering), -1: fixed or not yet in
  std::vector<double> weight_;        // per factor: 1 once in the system, 0 while pending
  std::vector<char> robust_;          // per factor: the kernel applies
  std::vector<std::vector<size_t>> var_factors_;  // per variable: the factors in the system that touch it
  std::vector<int> pending_vars_;
  std::vector<size_t> pending_factors_;
  int used_ = 0, capacity_ = 0;
  size_t ordered_nnz_ = 0;
  int rebuilds_ = 0;
  size_t factors_in_system_ = 0;
  int64_t updates_ = 0;
  size_t update_limit() const;
  bool gauge_checked_ = false;
  cholmod_common common_{};
  cholmod_factor* L_ = nullptr;
  Eigen::VectorXd g_;                 // gradient J' W e at the linearization point, by column
  Eigen::VectorXd dx_;                // solution, by column
};

}  // namespace sextant::graph
