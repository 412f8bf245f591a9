#pragma once
// Batch nonlinear least squares on a factor graph: Gauss-Newton or Levenberg-Marquardt with increments on the
// manifold (X <- X (+) dx), normal equations on CHOLMOD (sparse_normal_equations.hpp).  Never throws for bad data:
// every failure (NaN input, non-positive-definite information, an under-constrained or disconnected variable,
// a CHOLMOD failure) comes back as a status with a message.
#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/robust_kernel.hpp"
#include "estimators/graph/ordering.hpp"

#include <string>

namespace sextant::graph {

enum class Method { kGaussNewton, kLevenbergMarquardt };

struct OptimizerOptions {
  Method method = Method::kGaussNewton;
  int max_iterations = 100;
  /// Stop when chi2 decreases by less than this fraction in an iteration (g2o's -gain, Ceres' function tolerance).
  double relative_tolerance = 1e-6;
  /// Levenberg-Marquardt: initial damping relative to diag(H) and its adaptation (Nielsen 1999).
  double initial_lambda = 1e-5;
  RobustKernel kernel = RobustKernel::kNone;
  double kernel_width = 1.0;  // Huber/Cauchy delta, or DCS phi
  Ordering ordering = Ordering::kBlockAmd;
  /// Fix the first pose when nothing is fixed and no factor is a prior (the gauge).
  bool fix_first_pose_if_no_gauge = true;
};

enum class Termination { kConverged, kMaxIterations, kNoProgress, kFailure };

struct OptimizerSummary {
  Termination termination = Termination::kFailure;
  std::string message = "not run";
  int iterations = 0;  // accepted steps plus rejected LM trials
  double initial_chi2 = 0, final_chi2 = 0;
  double initial_cost = 0, final_cost = 0;  // robust cost (equal to chi2 without a kernel)
  double linearize_seconds = 0, factorize_seconds = 0, solve_seconds = 0, total_seconds = 0;
  bool usable() const { return termination != Termination::kFailure; }
  bool converged() const { return termination == Termination::kConverged; }
};

/// Checks the graph before optimizing: finite values, symmetric positive definite information, factors that
/// reference existing variables.  Returns an empty string when fine, else what is wrong.
std::string validate(const FactorGraph& graph);
/// The same checks for one factor (`index` names it in the message).
std::string validate_factor(const std::vector<Variable>& vars, const Factor& factor, size_t index);

/// Optimizes the graph's variables in place.
OptimizerSummary optimize(FactorGraph& graph, const OptimizerOptions& options);

}  // namespace sextant::graph
