#pragma once

namespace sextant::engine {

/// Dead reckoning: each odometry source's increments composed into a pose in the map frame, with propagated
/// covariance.  The first message of a source anchors it at the map origin (or at `initial_*`).
struct DeadReckoningConfig {
  bool enabled = true;
  /// Floor of the eigenvalues of every increment covariance (m^2, rad^2; estimators/spd_matrix.hpp), so a sender
  /// that reports zero motion noise still yields a positive-definite fused covariance.
  double min_increment_variance = 1e-12;
  /// A gap between consecutive messages of a source longer than this (seconds) is reported (counter
  /// "odometry_gaps") but still composed: odometry is relative, a gap loses no information.
  double max_gap_s = 1.0;
};

}  // namespace sextant::engine
