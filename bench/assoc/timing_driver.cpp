// Timing driver of bench/assoc/compare_timing.sh: run_assoc_experiment with the options of `sextant assoc-sim`
// (spacing 1, P_D 0.9, classic cost, LR at its default gap); prints median CPU ms per scan, build ms, correct rate, gap
// mean and max, mean tuple count.
#include "sim/assoc_experiment.hpp"
#include <cstdio>
#include <cstdlib>
#include <cstring>
int main(int argc, char** argv) {
  sextant::tools::AssocExperimentOptions o;
  o.spacing = 1;
  o.p_detect = 0.9;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (!strcmp(a, "--sensors"))
      o.sensors = atoi(argv[++i]);
    else if (!strcmp(a, "--targets"))
      o.targets = atoi(argv[++i]);
    else if (!strcmp(a, "--clutter"))
      o.clutter = atof(argv[++i]);
    else if (!strcmp(a, "--runs"))
      o.runs = atoi(argv[++i]);
    else if (!strcmp(a, "--seed"))
      o.seed = strtoull(argv[++i], nullptr, 10);
    else if (!strcmp(a, "--uniform"))
      o.uniform_layout = true;
    else if (!strcmp(a, "--target-prior"))
      o.target_prior = true;
  }
  const auto r = sextant::tools::run_assoc_experiment(o);
  std::printf("%.3f %.3f %.4f %.4f %.4f %.1f\n", r.median_cpu_ms, r.build_median_ms, r.correct_rate, r.gap_mean,
              r.gap_max, r.tuples_mean);
}
