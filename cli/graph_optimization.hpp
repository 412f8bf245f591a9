#pragma once
// `sextant optimize` as a function, for the CLI and the Python module: initialize and optimize a pose graph (batch
// Gauss-Newton / Levenberg-Marquardt on CHOLMOD), or feed it to the incremental smoother one pose per update and
// compare with a batch solve from the same start.  The summary carries the keys of `sextant optimize --json`
// (the keys scripts depend on: vertices, edges, dimension, iterations, initial_chi2, final_chi2, solve_seconds, converged; with
// `incremental` also step_ms_mean/p50/p99/max and final_chi2_batch_ratio); chi2 is g2o's, the sum of eᵀΩe.
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/incremental_options.hpp"
#include "estimators/graph/optimizer.hpp"
#include "estimators/graph/robust_kernel.hpp"
#include "estimators/graph/ordering.hpp"
#include "report/summary.hpp"

#include <string>
#include <vector>

namespace sextant::tools {

/// Where the batch optimization starts.
enum class InitialEstimate {
  kAuto,      // "auto": the chordal estimate when its chi2 is below the file's, else the file's
  kFile,      // "file": the file's vertices
  kOdometry,  // "odometry": composed along a spanning tree of the odometry edges
  kChordal,   // "chordal": rotation relaxation (graph::initialize_chordal)
  kSgd,       // "sgd": Olson's SGD from the odometry (planar graphs)
};

/// The spellings of the kinds `sextant optimize` and the Python module's optimize() take, one table per kind
/// (graph_optimization.cpp; the robust kernels' is graph::robust_kernel_from_name, robust_kernel.hpp).  *_from_name throws std::invalid_argument naming the option and its spellings for any
/// other name; *_names lists the spellings (for the command line's checks).
graph::Method solver_from_name(const std::string& name);              // gn | lm
InitialEstimate initial_estimate_from_name(const std::string& name);  // auto | file | odometry | chordal | sgd
graph::Ordering ordering_from_name(const std::string& name);          // block-amd | amd | colamd | metis | auto
const char* name_of(graph::Method solver);
const char* name_of(InitialEstimate init);
const char* name_of(graph::Ordering ordering);
std::vector<std::string> solver_names();
std::vector<std::string> initial_estimate_names();
std::vector<std::string> ordering_names();

struct GraphOptimizationOptions {
  graph::Method solver = graph::Method::kGaussNewton;
  InitialEstimate init = InitialEstimate::kAuto;
  graph::RobustKernel robust = graph::RobustKernel::kNone;
  graph::Ordering ordering = graph::Ordering::kBlockAmd;
  int max_iters = 100;
  double kernel_width = 1.0;                             // Huber/Cauchy delta or DCS phi
  double tolerance = 1e-6;                               // stop when chi2 decreases by less than this fraction
  bool incremental = false;                              // one pose per update through the incremental smoother
  double relin_translation = 0.1, relin_rotation = 0.1;  // incremental: relinearization thresholds (m, rad)
  int relin_skip = 1;  // incremental: look for variables to relinearize every this many updates
  int relin_heavy_every = graph::IncrementalOptions{}.heavy_relinearize_every;  // incremental: ... and those over the
                                                                                // work budget alone every this many
  std::string step_trace;  // incremental: a CSV file of every update (write_step_trace's columns); empty: none
  int step_reference = 0;  // incremental, with step_trace: the batch optimum's chi2 every this many updates (0: none)
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

/// Throws std::invalid_argument for options that do not combine (--incremental with an --init or --solver) or are out
/// of range and std::runtime_error when an initializer fails or `output` cannot be written.  `output` (may be
/// empty) receives the optimized graph in g2o format.  `g` is optimized in place in batch mode.
GraphOptimizationResult optimize_graph(graph::G2oGraph& g, const GraphOptimizationOptions& options,
                                       const std::string& output = "");

}  // namespace sextant::tools
