#pragma once
// The incremental smoother's options and the status of one update (incremental_smoother.hpp says what the smoother
// computes).  No CHOLMOD here: configuration, runtime and replay headers include this one.
//
// Units: a variable's step is compared component-wise: translation components (metres, point coordinates) against
// `relinearize_translation`, rotation components (radians) against `relinearize_rotation`; times are milliseconds.
#include "estimators/graph/robust_kernel.hpp"

#include <atomic>
#include <cstdint>
#include <string>

namespace sextant::graph {

struct IncrementalOptions {
  double relinearize_translation = 0.1;  // m: relinearize a variable whose step exceeds this in a translation component
  double relinearize_rotation = 0.1;     // rad: ... or this in a rotation component
  /// Relinearize + re-solve rounds per update.  One: what a round leaves (variables beyond the work budget, or moved
  /// by its re-solve) waits for the next update, as the budget already makes it wait; a second round cost torus3D a
  /// tenth of its mean step, sphere2500 2 %, for the same online answer (within the same 1e-4 of the batch optimum at
  /// every sampled update on all four sets, bench/results/incremental_isam2.md).
  int relinearization_passes = 1;
  int relinearize_skip = 1;  // look for variables to relinearize every this many updates (iSAM2's relinearizeSkip)
  /// Factors changed by rank updates in one round (new ones or relinearized ones) beyond which a rebuild is cheaper:
  /// max(min_update_factors, update_fraction x factors in the system), at most max_update_factors.  The cap matters on
  /// large graphs, where each factor's path to the root is long: on city10000 relinearizing 158 factors by rank
  /// updates took 80-90 ms, more than a rebuild; below 6400 factors it changes nothing (bench/RESULTS.md).
  double update_fraction = 0.02;
  int min_update_factors = 32;
  int max_update_factors = 128;
  /// Rank-update work one relinearization round may spend (sum over its factors of residual dimension x the column
  /// counts of L along the factor's path to the root: the entries CHOLMOD's update touches).  The variables whose
  /// steps are furthest past the thresholds go first; the others wait for the next updates, so that a correction
  /// spreads over several updates instead of spiking one (sphere2500: 40-80 factors at once took 130-370 ms).
  double relinearize_work = 4e6;
  /// A variable whose relinearization alone costs more than relinearize_work (the budget takes the most-moved one
  /// whatever it costs) is relinearized only at every this many-th update (iSAM2's relinearizeSkip, for these only);
  /// cheaper ones at every update.  On 3-D graphs such variables (one pose's few factors on paths through the dense top
  /// of L) took three quarters of the relinearization time, relinearized again and again as a correction moved them
  /// (torus3D: 2,525 of 5,959 rounds).  Every 10th: torus3D's mean step 0.58 of every update's, the online answer as
  /// close to the batch optimum; planar graphs have none (bench/results/incremental_isam2.md).
  int heavy_relinearize_every = 10;
  int rebuild_iterations = 10;  // Gauss-Newton iterations of a rebuild for new factors that would cost more as
                                // rank updates (until no variable moves past the thresholds); a rebuild for
                                // relinearization or reordering takes one
  double refill_ratio = 1.5;    // rebuild (reorder) when nnz(L) exceeds this multiple of its size after ordering
                                // (city10000: 1.5 takes 0.68 of the CPU time of 2.5, 1.25 0.62 with more rebuilds)
  /// Orderings at rebuilds: constrained AMD with the newest variables last up to this many variables, METIS nested
  /// dissection above (city10000: half the factorization flops; M3500: its ordering time outweighs the gain).
  int nested_dissection_above = 5000;
  double capacity_growth = 1.0;  // reserved columns at a rebuild: this fraction of the used ones (and >= 64)
  /// Updates over which a fill-triggered reordering, or a first factorization begun by begin_spread_build, is spread
  /// (incremental_smoother.hpp); 0: reorder within the update.
  int reorder_spread = 8;
  /// Spread reorderings (and rebuilds for relinearization) only in systems of more than this many variables, or
  /// whose factor L has more than reorder_spread_nonzeros entries: below both, a rebuild takes a few ms (intel, 95,000
  /// entries at its end: spread or not, the same mean, p99 and max within 10 %), and spreading it would hold two
  /// factors at once for little.  M3500 passes 50,000 entries early: spread, its p99 step is 0.47x and its max 0.66x
  /// (median of 5 interleaved runs each), its mean 1.07x, and peak RSS +3 MB.  3-D graphs fill in: sphere2500's
  /// rebuilds took 150-350 ms with 0.8-1.6 million entries in L, at 1000-2500 poses.
  int reorder_spread_above = 5000;
  int reorder_spread_nonzeros = 50000;
  /// ... or more factors: a rebuild relinearizes every factor, and a map of landmarks seen from every keyframe has
  /// many (a 5-minute simulated planar run: 1,800 keyframes, 15,000 factors, 5 Mflop of factorization, and its
  /// fill-triggered rebuilds took 20-40 ms, most of it relinearizing the sightings).
  int reorder_spread_factors = 6000;
  /// ms: an update works on a spread reordering until this long after it began, and at least for its even share of
  /// the work left (ReorderScheduler::remaining_ms), so that the installing update is left little.
  double reorder_slice_ms = 4.0;
  /// Wildfire threshold of the back-substitution (as iSAM2's): a change of a step by less than this (m or rad) is not
  /// propagated to the variables that depend on it (they keep a value stale by less than it).  0: exact.
  double wildfire = 1e-3;
  RobustKernel kernel = RobustKernel::kNone;
  double kernel_width = 1.0;
  /// Not configuration: a flag of the smoother's owner that asks a rebuild in progress to end after the
  /// Gauss-Newton iteration under way (the first one always completes, so a factorization of the current
  /// linearization is in place and the estimates are those of the last iteration done: a consistent state, as a
  /// rebuild that converged early leaves).  Read between iterations, from the smoother's thread, while another thread
  /// may set it: how the daemon's shutdown stops a long solve at its drain deadline (daemon/runtime/stage_runner.hpp).
  /// nullptr: never.
  const std::atomic<bool>* interrupt = nullptr;
  /// Fault injection, for tests of the callers' recovery: the first factorization (a rank update or a numeric
  /// factorization) at or after update() call number N (1, 2, ...) fails as CHOLMOD does when it runs out of memory.
  /// 0: never.
  int64_t fail_factorization_at_update = 0;
};

/// Empty when every option is within its range, else the first option that is not, with its value and the range
/// ("relinearize_translation = -1: must be a positive number").  The smoother's constructor refuses such options.
std::string invalid_option(const IncrementalOptions& options);

/// Why an update's estimate is not the answer (as Ceres' Solver::Summary says whether its solution is usable).
enum class SmootherFailure {
  kNone,
  /// The normal equations are not positive definite: a variable no factor determines (under-constrained, or
  /// disconnected from the gauge); the message names it.  The factorization is dropped and the next update rebuilds
  /// it (and fails the same way while the variable is in the system and undetermined).
  kUnderdetermined,
  /// CHOLMOD failed (it ran out of memory, or a fault was injected): the factorization is dropped and the next
  /// update() or rebuild() builds it afresh from the graph; the estimates are those of the last good update.
  kFactorization,
};

struct IncrementalStatus {
  bool ok = true;  // failure == kNone: the estimates are this update's solution
  SmootherFailure failure = SmootherFailure::kNone;
  std::string message;  // why !ok
  int new_variables = 0, new_factors = 0;
  int deferred_variables = 0;  // new variables not yet determined by their factors (kept pending)
  int relinearized_variables = 0, relinearized_factors = 0;
  bool rebuilt = false;      // the system was reordered and refactorized in this update (or a spread
                             // reordering was put in place)
  bool interrupted = false;  // a rebuild ended at IncrementalOptions::interrupt before it converged
  bool building = false;     // a spread first factorization is under way (begin_spread_build): nothing was solved,
                             // the estimates are those it began with (new variables at their initial values)
  int solves = 0;
};

}  // namespace sextant::graph
