#pragma once
// Feeding a whole graph to the incremental smoother as a robot would have produced it, one pose per update: update k
// brings pose k (in the file's vertex order) and every factor whose latest pose is k, in file order (so its odometry
// edge and the loop closures that arrived with it; the standard data sets list all odometry first and all loops
// after, so a literal line-by-line feed would be one odometry-only pass and one batch problem at the end).  A
// variable enters with the first factor that references it, initialized by composing that relative-pose measurement
// with the end already estimated (the previous pose's current estimate and the odometry, as GTSAM's
// timeIncremental does), else with the file's value.  This is how `sextant optimize --incremental` and the
// incremental benchmarks measure per-step latency, the same feed as the iSAM2 peer's driver uses (one pose per
// update, its time being the update plus the new pose's estimate).
#include "estimators/graph/incremental_smoother.hpp"

#include <limits>
#include <string>
#include <vector>

namespace sextant::graph {

/// One update as the feed saw it: what the smoother did (its time is FeedResult::step_ms; `sextant optimize
/// --step-trace`).
struct FeedStep {
  IncrementalStatus status;
  size_t factor_nonzeros = 0;  // nnz(L) after the update
  bool reordering = false;     // a spread reordering is under way after it
  /// With FeedOptions::chi2: chi2 of the factors so far at the smoother's estimate after the update (its online
  /// answer); at the updates FeedOptions::reference_every picks, the batch optimum's chi2 of the same factors
  /// (Gauss-Newton to convergence from that estimate).  NaN otherwise.  Neither is in the update's time.
  double chi2 = std::numeric_limits<double>::quiet_NaN();
  double batch_chi2 = std::numeric_limits<double>::quiet_NaN();
};

/// What the feed measures beyond each update's time.
struct FeedOptions {
  bool chi2 = false;        // FeedStep::chi2 after every update
  int reference_every = 0;  // FeedStep::batch_chi2 every this many updates and at the last (0: never)
};

struct FeedResult {
  std::vector<double> step_ms;  // wall time of each update()
  std::vector<FeedStep> steps;  // the same updates, what the smoother did in each
  int rebuilds = 0, relinearized_factors = 0, deferred_at_end = 0;
  bool ok = true;
  std::string message;  // the first failed update's message
  FactorGraph start;    // the smoother's variables with the initial values they were given, and the factors
};

/// Feeds `graph` (variables and factors, e.g. from read_g2o) to `smoother`, which must be empty.  The variables'
/// `fixed` flags are kept.  Stops at the first failed update.
FeedResult feed_in_order(const FactorGraph& graph, IncrementalSmoother& smoother, const FeedOptions& options = {});

}  // namespace sextant::graph
