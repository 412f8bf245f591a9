// optimize_g2o INPUT.g2o [OUTPUT.g2o]: reads a pose graph, initializes it as `sextant optimize` does by default (the
// chordal estimate when its chi2 is below the file's), optimizes it with Gauss-Newton (sextant's defaults), prints a
// JSON summary and writes the optimized graph.
// Only sextant::estimators is linked: no daemon, no LCM.
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/initialization.hpp"
#include "estimators/graph/optimizer.hpp"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s INPUT.g2o [OUTPUT.g2o]\n", argv[0]);
    return 2;
  }
  sextant::graph::G2oGraph g;
  try {
    g = sextant::graph::read_g2o(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  sextant::graph::initialize_auto(g.graph);
  const sextant::graph::OptimizerOptions options;  // Gauss-Newton, at most 100 iterations, relative tolerance 1e-6
  const sextant::graph::OptimizerSummary s = sextant::graph::optimize(g.graph, options);
  std::printf(
      "{\"vertices\": %zu, \"edges\": %zu, \"dimension\": %d, \"iterations\": %d, \"initial_chi2\": %.17g, "
      "\"final_chi2\": %.17g, \"converged\": %s}\n",
      g.graph.variables().size(), g.graph.factors().size(), g.dimension, s.iterations, s.initial_chi2, s.final_chi2,
      s.converged() ? "true" : "false");
  if (argc == 3) sextant::graph::write_g2o(argv[2], g.graph);
  if (!s.usable()) {
    std::fprintf(stderr, "optimization failed: %s\n", s.message.c_str());
    return 1;
  }
  return 0;
}
