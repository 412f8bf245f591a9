// The passive-association paper's experiment reproduces its sanity anchors: two targets at d = 0 are associated correctly
// exactly a quarter of the time (the two tuples are indistinguishable; each of the 4 detection pairings of the
// second and third sensors is equally likely), and at d = 2 km with 5 mrad almost always.  The relaxation matches
// the exact solver, the duality gap stays within 1 % on scans that once stalled above it, the target-prior term
// cuts ghosts under clutter, and the sensor layouts are sim/assoc_experiment.hpp's.
#include "sim/assoc_experiment.hpp"

#include "assoc/sd_assignment.hpp"

#include <doctest/doctest.h>

using namespace sextant::tools;

namespace {

// A scenario of the experiment: `targets` targets at separation `spacing` km, detection probability, mean false
// alarms per sensor and scan, Monte Carlo runs; the rest at the defaults (3 sensors, 5 mrad, classic cost, grid).
AssocExperimentOptions scenario(int targets, double spacing, double p_detect, double clutter, int runs) {
  return {.targets = targets, .spacing = spacing, .runs = runs, .p_detect = p_detect, .clutter = clutter};
}

}  // namespace

TEST_CASE("association sanity anchors: d = 0 gives 1/4, d = 2 km at 5 mrad gives ~1") {
  auto o = scenario(2, 0.0, 1.0, 0.0, 600);
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
  auto o = scenario(6, 1.0, 0.9, 2, 30);
  o.compare_exact = true;
  const auto lr = run_assoc_experiment(o);
  CHECK(lr.exact_compared == 30);
  CHECK(lr.gap_max <= 0.01);
  // The default gap (0.01 cost units, then the branch and bound) finds the optimum on every scan, and so does a
  // gap of 0.
  o.gap_tolerance = 0;
  const auto full = run_assoc_experiment(o);
  MESSAGE("LR optimal on " << lr.lr_optimal << " of 30 at the default gap, " << full.lr_optimal << " of 30 at 0");
  CHECK(lr.lr_optimal == 30);
  CHECK(full.lr_optimal == 30);
  o.gap_tolerance = sextant::assoc::kDefaultGapTolerance;
  o.compare_exact = false;
  o.exact = true;
  const auto exact = run_assoc_experiment(o);
  CHECK(std::abs(lr.correct_rate - exact.correct_rate) <= 2 * exact.correct_rate_stderr + 0.01);
}

TEST_CASE("the duality gap stays within 1 % on the grid scans that once stalled above it") {
  // Grid 3 x 20 + 5 false alarms, the timing scenario (bench/assoc/timing_driver.cpp's options), seed 1:
  // scan 80 (0-based) ended at 1.18 % (a three-tuple component with a fractional LP bound) and, with the target
  // prior, scan 159 at 1.87 % (an upper bound 1.7 % above the optimum that only a relaxation of another sensor
  // recovers).  The generator is sequential, so the runs up to those scans are replayed.
  auto o = scenario(20, 1.0, 0.9, 5, 81);
  const auto plain = run_assoc_experiment(o);
  o.runs = 160;
  o.target_prior = true;
  const auto prior = run_assoc_experiment(o);
  MESSAGE("gap max " << plain.gap_max << " (81 scans), with the prior " << prior.gap_max << " (160 scans)");
  CHECK(plain.gap_max <= 0.01);
  CHECK(prior.gap_max <= 0.01);
}

TEST_CASE("the target-prior term cuts ghost tuples under clutter") {
  auto o = scenario(2, 2.0, 0.9, 1, 300);
  const auto plain = run_assoc_experiment(o);
  o.target_prior = true;
  const auto prior = run_assoc_experiment(o);
  MESSAGE("ghosts per scan " << plain.ghosts_per_scan << " -> " << prior.ghosts_per_scan << ", correct "
                             << plain.correct_rate << " -> " << prior.correct_rate);
  CHECK(prior.ghosts_per_scan < 0.5 * plain.ghosts_per_scan);
  CHECK(prior.correct_rate > plain.correct_rate + 3 * plain.correct_rate_stderr);
}

TEST_CASE("sensor layouts and the uniform target layout") {
  const auto five = assoc_experiment_sensors(5), seven = assoc_experiment_sensors(7);
  REQUIRE(five.size() == 5);
  REQUIRE(seven.size() == 7);
  CHECK(five[3] == Eigen::Vector3d(30, 30, 0.1));
  CHECK(five[4] == Eigen::Vector3d(15, -10, 0));
  CHECK(seven[6] == Eigen::Vector3d(40, 15, 0.05));  // sees the region around azimuth pi: the field of view wraps
  CHECK(assoc_experiment_sensors(9).size() == 9);
  auto o = scenario(20, 1.5, 0.9, 5, 5);
  o.sensors = 7;
  o.uniform_layout = true;
  o.target_prior = true;
  const auto r = run_assoc_experiment(o);
  CHECK(r.observable_targets == 100);  // 7 sensors at P_D 0.9: every target is seen by >= 2 of them (P ~ 1 - 6e-6)
  CHECK(r.correct_rate > 0.8);
  CHECK(r.gap_max <= 0.01);
}

TEST_CASE(
    "coplanar grid, 3 x 20, P_D 1: the default relaxation reaches the optimum of its cost where a loose gap did not") {
  // d = 0.5 km, 12 scans.  The old rule stopped at a relative gap of 1 % of |UB|, about 6.3 cost units on these
  // scans (|UB| ~ 635, nearly all of it the constant per-detection term); an absolute gap of 6.3 reproduces it.  The
  // default (0.01 units, then the branch and bound) finds the optimum on every scan, proven by the exact solver.
  auto o = scenario(20, 0.5, 1.0, 0.0, 12);
  o.compare_exact = true;
  o.gap_tolerance = 6.3;
  const auto loose = run_assoc_experiment(o);
  o.gap_tolerance = sextant::assoc::kDefaultGapTolerance;
  const auto tight = run_assoc_experiment(o);
  MESSAGE("optimal on " << loose.lr_optimal << " of " << loose.exact_compared << " at a 6.3 gap, " << tight.lr_optimal
                        << " at the default");
  CHECK(tight.exact_unproven == 0);
  CHECK(tight.exact_compared == 12);
  CHECK(tight.lr_optimal == 12);
  CHECK(loose.lr_optimal <= 8);
  CHECK(tight.absolute_gap_mean <= 0.01);
}
