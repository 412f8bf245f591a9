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
// When a round would relinearize more than `full_relinearization_fraction` of the factors, when the reserved
// columns run out, or when the factor has filled in past `refill_ratio` times its size after the last ordering, the
// system is rebuilt: every factor relinearized at the current estimate, a fresh block-AMD ordering (newest variables
// last), and a numeric factorization (supernodal, then converted to the simplicial LDL' form the updates need).
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
  double relinearize_translation = 0.05;  // m: relinearize a variable whose step exceeds this in a translation component
  double relinearize_rotation = 0.05;     // rad: ... or this in a rotation component
  int relinearization_passes = 2;         // relinearize + re-solve rounds per update
  double full_relinearization_fraction = 0.25;  // beyond this share of factors a round rebuilds the whole system
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
  /// an unknown variable or its information is not finite, symmetric and positive definite.
  void add_factor(std::unique_ptr<Factor> factor);
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
  /// Scalar unknowns in the factorized system, the nonzeros of L, and how many rebuilds happened.
  int dimension() const { return used_; }
  size_t factor_nonzeros() const;
  int rebuilds() const { return rebuilds_; }
  const IncrementalOptions& options() const { return options_; }

 private:
  struct Contribution;  // one factor's (W^1/2 J)' and J' W e at the linearization point
  Contribution linearize(size_t factor) const;
  void apply(const Contribution& c, bool add);
  bool determined(const std::vector<int>& new_vars, const std::vector<size_t>& new_factors,
                  std::vector<char>& ready) const;
  void solve();
  std::vector<int> moved_variables() const;
  bool relinearize(const std::vector<int>& vars, IncrementalStatus& st);
  std::string factorize_all();

  IncrementalOptions options_;
  FactorGraph graph_;                 // estimates and factors
  std::vector<Variable> lin_;         // linearization points
  std::vector<int> pos_;              // per variable: first column in L (the ordering), -1: fixed or not yet in
  std::vector<double> weight_;        // per factor: robust weight at its linearization (0: not yet in the system)
  std::vector<std::vector<size_t>> var_factors_;  // per variable: the factors in the system that touch it
  std::vector<int> pending_vars_;
  std::vector<size_t> pending_factors_;
  int used_ = 0, capacity_ = 0;
  size_t ordered_nnz_ = 0;
  int rebuilds_ = 0;
  bool gauge_checked_ = false;
  cholmod_common common_{};
  cholmod_factor* L_ = nullptr;
  Eigen::VectorXd g_;                 // gradient J' W e at the linearization point, by column
  Eigen::VectorXd dx_;                // solution, by column
};

}  // namespace sextant::graph
