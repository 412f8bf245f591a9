#pragma once
// Source C's passive-association experiment (issue 6; assoc.md §4 B0): S static sensors, targets placed at a given
// separation, bearings with Gaussian noise, detection probability and Poisson clutter; each Monte Carlo run builds
// the tuples, solves the S-D assignment and scores it.  Deterministic for a seed.
//  - 3 sensors: the paper's positions (30, 0, 0.1), (0, 30, 0.1), (0, 0, 0); more sensors are placed on a circle
//    of radius 30 around (15, 15) at heights 0-0.5.  Units are the paper's (km), angles in rad.
//  - 2 targets: at c and c + (d, 0, 0), c uniform in [5, 25] x [5, 25] x [2, 8].  More targets: a horizontal grid
//    of spacing d at z = 5 centred at (15, 15) (assoc.md Layout A: coplanar, the hardest for ghosts).
//  - Clutter: Poisson(clutter) false alarms per sensor and scan, uniform over that sensor's azimuth-elevation box of
//    the target region padded by 5 sigma; the cost's clutter density is clutter / box area (at least 1e-3).
//  - Correct: a target detected by >= 2 sensors whose exact tuple of detections is among the output tuples.
#include "assoc/tuple_costs.hpp"

#include <cstdint>
#include <string>

namespace sextant::replay {

struct AssocExperimentOptions {
  int sensors = 3;
  int targets = 2;
  double spacing = 1.0;     // km
  double sigma = 0.005;     // rad
  int runs = 1000;
  assoc::CostKind cost = assoc::CostKind::kClassic;
  double alpha = 0.5;
  bool exact = false;       // exact branch and bound instead of Lagrangian relaxation
  double p_detect = 1.0;
  double clutter = 0.0;     // mean false alarms per sensor per scan
  uint64_t seed = 1;
};

struct AssocExperimentResult {
  int64_t observable_targets = 0, correct = 0, ghost_tuples = 0, output_tuples = 0;
  double correct_rate = 0, correct_rate_stderr = 0;
  double ghosts_per_scan = 0;
  double position_rmse = 0;    // km, over correctly associated targets
  double mean_ms = 0;          // per scan, tuple building + assignment
  double gap_mean = 0;
  double tuples_mean = 0;
};

AssocExperimentResult run_assoc_experiment(const AssocExperimentOptions& options);

}  // namespace sextant::replay
