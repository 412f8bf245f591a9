// Source C's experiment reproduces the sanity anchors of issue 6: two targets at d = 0 are associated correctly
// exactly a quarter of the time (the two tuples are indistinguishable; each of the 4 detection pairings of the
// second and third sensors is equally likely), and at d = 2 km with 5 mrad almost always.
#include "replay/assoc_experiment.hpp"

#include <doctest/doctest.h>

using namespace sextant::replay;

TEST_CASE("association sanity anchors: d = 0 gives 1/4, d = 2 km at 5 mrad gives ~1") {
  AssocExperimentOptions o;
  o.runs = 600;
  o.spacing = 0;
  const auto zero = run_assoc_experiment(o);
  CHECK(std::abs(zero.correct_rate - 0.25) < 4 * zero.correct_rate_stderr + 0.01);
  o.spacing = 2.0;
  const auto far = run_assoc_experiment(o);
  CHECK(far.correct_rate > 0.98);
  CHECK(far.gap_mean < 0.01);
  CHECK(far.position_rmse < 0.3);
  for (auto cost : {sextant::assoc::CostKind::kKl, sextant::assoc::CostKind::kRenyi}) {
    o.cost = cost;
    o.runs = 200;
    CHECK(run_assoc_experiment(o).correct_rate > 0.95);
  }
}

TEST_CASE("Lagrangian relaxation matches the exact solver on 6-target scans") {
  AssocExperimentOptions o;
  o.targets = 6;
  o.spacing = 1.0;
  o.runs = 30;
  const auto lr = run_assoc_experiment(o);
  o.exact = true;
  const auto exact = run_assoc_experiment(o);
  // At the default 1 % duality-gap tolerance the relaxation may stop short of the optimum on a few scans.
  CHECK(std::abs(lr.correct_rate - exact.correct_rate) <= 2 * exact.correct_rate_stderr + 0.01);
  CHECK(lr.gap_mean <= 0.01);
}
