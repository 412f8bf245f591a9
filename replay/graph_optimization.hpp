#pragma once
// `sextant optimize` as a function, for the CLI and the Python module: initialize and optimize a pose graph (batch
// Gauss-Newton / Levenberg-Marquardt on CHOLMOD), or feed it to the incremental smoother one pose per update and
// compare with a batch solve from the same start.  The summary carries the keys of `sextant optimize --json`
// (DESIGN.md: vertices, edges, dimension, iterations, initial_chi2, final_chi2, solve_seconds, converged; with
// `incremental` also step_ms_mean/p50/p99/max and final_chi2_batch_ratio); chi2 is g2o's, the sum of eᵀΩe.
#include "estimators/graph/g2o_io.hpp"
#include "replay/summary.hpp"

#include <string>
#include <vector>

namespace sextant::replay {

struct GraphOptimizationOptions {
  std::string solver = "gn";            // gn | lm
  std::string init = "auto";            // auto (chordal when it lowers chi2, else file) | file | odometry | chordal | sgd
  std::string robust = "none";          // none | huber | cauchy | dcs
  std::string ordering = "block-amd";   // block-amd | amd | colamd | metis | auto
  int max_iters = 100;
  double kernel_width = 1.0;            // Huber/Cauchy delta or DCS phi
  double tolerance = 1e-6;              // stop when chi2 decreases by less than this fraction
  bool incremental = false;             // one pose per update through the incremental smoother
  double relin_translation = 0.1, relin_rotation = 0.1;  // incremental: relinearization thresholds (m, rad)
  int relin_skip = 1;                   // incremental: look for variables to relinearize every this many updates
};

struct GraphOptimizationResult {
  Summary summary;
  /// False when the run failed (the optimizer's or the smoother's message is in `message`); the summary is filled
  /// as far as it got.
  bool ok = false;
  std::string message;
  /// The optimized variables (poses and points) in the graph's order.
  std::vector<graph::Variable> variables;
};

/// Throws std::invalid_argument for options that do not exist or do not combine (--incremental with an --init or
/// --solver) and std::runtime_error when an initializer fails or `output` cannot be written.  `output` (may be
/// empty) receives the optimized graph in g2o format.  `g` is optimized in place in batch mode.
GraphOptimizationResult optimize_graph(graph::G2oGraph& g, const GraphOptimizationOptions& options,
                                       const std::string& output = "");

}  // namespace sextant::replay
