#pragma once
// Consistency of the EKF on simulated runs (Bar-Shalom, Li & Kirubarajan 2001, §5.4; Bailey et al., "Consistency
// of the EKF-SLAM algorithm", IROS 2006): over N independent runs (seeds), the normalized estimation error squared
// of the pose, NEES_k = e_k' P_k^-1 e_k with e_k = Log(X_hat_k^-1 X_true_k) over [x, y, yaw] and P_k the published
// FUSED_POSE covariance (right perturbation, body frame), is averaged per time step into ANEES_k.  For a consistent
// filter N * ANEES_k ~ chi-square(3 N), so ANEES_k lies inside [chi2(3N, 0.025), chi2(3N, 0.975)] / N (the 95 %
// bounds) about 95 % of the time.
// 3-D runs (`simulation.scenario` "spatial"): e = Log(X_hat^-1 X_true) over all 6 dof with the 6x6 covariance,
// bounds chi2(6N, .)/N.
// Each run: `sextant simulate` with the seed, its odometry and landmark events fed in order
// through the filter stage, localization against the simulator's landmarks (known map) or EKF-SLAM (no map).
#include "daemon/engine/filter_stage_config.hpp"
#include "sim/simulator.hpp"

#include <vector>

namespace sextant::tools {

struct ConsistencyOptions {
  int runs = 10;
  uint64_t first_seed = 1;       // seeds first_seed .. first_seed + runs - 1
  bool slam = false;             // false: localization against the true landmark map
  int every = 10;                // a NEES sample every this many odometry messages
  SimulationOptions simulation;  // seed ignored
  engine::FilterConfig filter;   // slam and map are set from the fields above
};

struct ConsistencyResult {
  std::vector<double> time_s;      // since the start of the run
  std::vector<double> anees;       // per sample, averaged over the runs
  double lower = 0, upper = 0;     // 95 % bounds of ANEES_k for `runs` runs (3 dof planar, 6 dof 3-D)
  double mean_anees = 0;           // ANEES averaged over the samples
  double fraction_inside = 0;      // of samples with ANEES_k inside [lower, upper]
  double final_position_rmse = 0;  // m, over the runs, at the last sample
};

/// Throws std::runtime_error when the simulation cannot be written (temporary file).
ConsistencyResult pose_nees_over_runs(const ConsistencyOptions& options);

}  // namespace sextant::tools
