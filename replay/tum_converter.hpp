#pragma once
// Ground truth (TUM format) -> simulated odometry, as an LCM log: at every ground-truth stamp, the true increment
// Delta_k = Q_(k-1)^-1 Q_k is corrupted on the right, Delta'_k = Delta_k Exp(eta_k + b_k |t_Delta|), with white
// noise eta ~ N(0, Q_k) (standard deviations proportional to the distance travelled, with a floor) and a constant
// drift b (a heading bias in rad per metre, a scale error on translation) that makes the odometry wander as
// visual odometry does.  The odometry_t messages carry the composed pose and the propagated covariance; the ground
// truth goes on GROUND_TRUTH (truth_t, kind "robot").  Deterministic for a seed.
#include <cstdint>
#include <string>

namespace sextant::replay {

struct TumConversionOptions {
  uint64_t seed = 1;
  double trans_noise = 0.01;   // m per m travelled (per axis)
  double rot_noise = 0.002;    // rad per m travelled (per axis)
  double min_sigma = 1e-4;     // floor of every standard deviation
  double yaw_drift = 0.002;    // rad per m travelled (bias about the body z axis)
  double scale_drift = 0.01;   // relative translation scale error
  std::string source = "camera";
  bool planar = false;
};

struct TumConversion {
  int64_t odometry = 0;
};

/// Throws std::runtime_error naming the line of a bad row of `gt_tum`.
TumConversion convert_tum(const std::string& gt_tum, const std::string& out_lcm, const TumConversionOptions& options = {});

}  // namespace sextant::replay
