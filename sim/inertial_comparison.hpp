#pragma once
// The inertial estimators against the truth on a simulated spatial run (`sextant simulate`, IMU + wheel odometry +
// GNSS with outages and multipath outliers): the wheel odometry alone (dead reckoning aligned with the truth at the
// start, today's odometry-only estimate), the error-state filter (estimators/inertial/error_state_ekf.hpp: IMU
// prediction, the odometry's body velocity, GNSS position behind a chi-square gate and GNSS velocity) and the
// fixed-lag keyframe smoother (estimators/inertial/inertial_smoother.hpp: IMU preintegration, odometry increments,
// robust GNSS positions), all started at the true pose and speed with unknown biases and fed the same messages in
// log order.  Scores at every odometry message after the first 10 s: the position error of each estimate.
#include "sim/simulator.hpp"

#include <cstdint>
#include <vector>

namespace sextant::tools {

struct InertialComparisonOptions {
  uint64_t seed = 1;
  double duration_s = 1200;
  double outage_period_s = 180, outage_duration_s = 60;  // no fix in the last 60 s of every 180 s
  double outlier_probability = 0.05;
  int smoother_window = 20;
  double keyframe_interval = 0.5;  // s
};

struct InertialScore {
  double ate = 0;              // position RMS over the run, m
  double ate_outage = 0;       // position RMS during the outages, m
  double drift = 0;            // worst over the outages: |error at its end - error at its start|, m
  double worst_with_gnss = 0;  // worst horizontal error while fixes come (5 s after an outage on), m
};

struct InertialComparison {
  InertialScore odometry, filter, smoother;
  int64_t gnss_fixes = 0, gnss_outliers = 0;  // outliers as simulated
  int64_t filter_gated = 0, smoother_down_weighted = 0;
  double filter_seconds = 0, smoother_seconds = 0;  // processing time of the whole run (wall clock)
  // The smoother's cost per keyframe (wall clock, s): median over the first and over the last 200 keyframes.
  double keyframe_cost_first = 0, keyframe_cost_last = 0;
  int64_t keyframes = 0;
  /// The filter's pose NEES at each scored odometry message: e^T P^-1 e over e = [p_true - p; Log(R^T R_true)] and the
  /// filter's covariance of [position, rotation error] (6 dof; chi-square(6) when the filter is consistent).
  std::vector<double> filter_nees;
};

/// Throws std::runtime_error when the simulation cannot be written (temporary file).
InertialComparison compare_inertial(const InertialComparisonOptions& options);

}  // namespace sextant::tools
