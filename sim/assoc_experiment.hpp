#pragma once
// The passive-association paper's experiment (Computer Measurement & Control 2015, see assoc/tuple_costs.hpp),
// extended to more sensors and targets: S static sensors, targets placed at a
// given separation, bearings with Gaussian noise, detection probability and Poisson clutter; each Monte Carlo run
// builds the tuples, solves the S-D assignment and scores it.  Deterministic for a seed.
//  - Sensors (km): the paper's (30, 0, 0.1), (0, 30, 0.1), (0, 0, 0); then sextant's (30, 30, 0.1),
//    (15, -10, 0), (-10, 15, 0.05), (40, 15, 0.05) (5 sensors: the first five, 7: all seven); beyond 7 on a circle
//    of radius 30 around (15, 15) at height 0.1.  Angles in rad.
//  - 2 targets: at c and c + (d, 0, 0), c uniform in [5, 25] x [5, 25] x [2, 8].  More targets, layout "grid": a
//    horizontal grid of spacing d at z = 5 centred at (15, 15) (coplanar, the hardest for
//    ghosts: with the sensors near z = 0, two targets whose difference is parallel to the baseline of two sensors
//    give lines of sight that meet exactly); layout "uniform": uniform in [5, 25] x [5, 25] x [2, 8] with minimum
//    separation d (rejection sampling).
//  - Field of view of a sensor (assoc/field_of_view.hpp): the azimuth-elevation bounding box of the target region
//    ([5, 25 + d] x [5, 25] x [2, 8], grown to hold the grid) seen from the sensor, padded by 5 sigma; its area psi_s
//    in rad^2.  Clutter: Poisson(clutter) false alarms per sensor and scan, uniform in that box.  The cost's
//    false-alarm density of sensor s is lambda_s = clutter / psi_s (with clutter 0: a nominal 0.1 / psi_s, since
//    the density must be positive; with P_D = 1 every tuple has S detections and it only shifts all costs alike).
//  - Target prior (optional): mu_T = targets / region volume (km^-3), see tuple_costs.hpp.
//  - Correct: a target detected by >= 2 sensors (observable) whose exact tuple of detections is in the output;
//    ghost: an output tuple that is no target's exact tuple.
//  - With `compare_exact` every scan is also solved exactly (branch and bound) on the same tuples, and the
//    relaxation's optimality (cost equal to the exact optimum) is counted over the scans whose optimum was proven.
//  - With `exact`, a scan whose optimum the branch and bound cannot prove within its budget is counted
//    (`exact_unproven`) and not scored; the rates are over the proven scans.
#include "assoc/tuple_costs.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace sextant::tools {

struct AssocExperimentOptions {
  int sensors = 3;
  int targets = 2;
  double spacing = 1.0;  // km
  double sigma = 0.005;  // rad
  int runs = 1000;
  assoc::CostKind cost = assoc::CostKind::kClassic;
  double alpha = 0.5;
  bool exact = false;           // exact branch and bound instead of Lagrangian relaxation
  bool compare_exact = false;   // also solve exactly and count where the relaxation reaches the optimum
  bool uniform_layout = false;  // more than 2 targets: uniform with minimum separation instead of the grid
  bool target_prior = false;    // add the target-prior term (mu_T = targets / region volume)
  double p_detect = 1.0;
  double clutter = 0.0;  // mean false alarms per sensor per scan
  int max_iterations = 100;
  double gap_tolerance = 0.01;  // absolute, cost units (assoc/sd_assignment.hpp)
  uint64_t seed = 1;
};

struct AssocExperimentResult {
  int64_t observable_targets = 0, correct = 0, ghost_tuples = 0, output_tuples = 0;
  double correct_rate = 0, correct_rate_stderr = 0;
  double ghosts_per_scan = 0;
  double position_rmse = 0;                       // km, over correctly associated targets
  double mean_ms = 0, median_ms = 0, p95_ms = 0;  // wall time per scan, tuple building + assignment
  double median_cpu_ms = 0;          // the same in thread CPU time (what the algorithm costs on a loaded machine)
  double build_median_ms = 0;        // thread CPU time per scan of tuple building (gating and costs) alone
  double gap_mean = 0, gap_max = 0;  // relative duality gap (UB - LB) / |UB|
  double absolute_gap_mean = 0;      // UB - LB in cost units
  double tuples_mean = 0;
  double iterations_mean = 0;
  int64_t exact_compared = 0, lr_optimal = 0;  // with compare_exact: scans compared, scans where LR was optimal
  // Scans the exact solver could not prove optimal within its node budget: with `exact` they are left out of every
  // figure above (not scored), with `compare_exact` they are not compared.
  int64_t exact_unproven = 0;
};

/// The sensor positions of the experiment (km), see above.
std::vector<Eigen::Vector3d> assoc_experiment_sensors(int count);

AssocExperimentResult run_assoc_experiment(const AssocExperimentOptions& options);

}  // namespace sextant::tools
