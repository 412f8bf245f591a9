#pragma once
// Feeding a whole graph to the incremental smoother in its factors' order, as a robot would have produced it: a
// variable enters when a factor first references it, initialized by composing a relative-pose measurement with the
// end already known (else with the graph's own value), and the smoother updates before each new pose enters, so one
// update holds a pose's odometry edge and the loop closures that arrived with it.  This is how
// `sextant optimize --incremental` and the incremental benchmarks measure per-step latency.
#include "estimators/graph/incremental_smoother.hpp"

#include <string>
#include <vector>

namespace sextant::graph {

struct FeedResult {
  std::vector<double> step_ms;       // wall time of each update()
  int rebuilds = 0, relinearized_factors = 0, deferred_at_end = 0;
  bool ok = true;
  std::string message;               // the first failed update's message
  FactorGraph start;                 // the smoother's variables with the initial values they were given, and the factors
};

/// Feeds `graph` (variables and factors, e.g. from read_g2o) to `smoother`, which must be empty.  The variables'
/// `fixed` flags are kept.  Stops at the first failed update.
FeedResult feed_in_order(const FactorGraph& graph, IncrementalSmoother& smoother);

}  // namespace sextant::graph
