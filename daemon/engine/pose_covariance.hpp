#pragma once
// The odometry covariances the stages compute from an odometry message: the plain-value definitions are in
// estimators/lie/pose_covariance.hpp (compose_covariance, nearest_psd and the increment's, found from here
// unqualified: the engine's namespace is inside sextant's).
#include "daemon/engine/events.hpp"
#include "estimators/filter/eigenvalue_floor.hpp"
#include "estimators/lie/pose_covariance.hpp"

namespace sextant::engine {

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message as the sender states it
/// (sextant::stated_increment_covariance).
inline Matrix6 stated_increment_covariance(const Odometry& odo, const SE3& delta,
                                           const Matrix6& previous_pose_covariance) {
  return sextant::stated_increment_covariance(odo.covariance, odo.increment_covariance, delta, previous_pose_covariance);
}

/// The increment covariance dead reckoning and the graph stage compose (sextant::regularized_increment_covariance).
inline Matrix6 increment_covariance(const Odometry& odo, const SE3& delta, const Matrix6& previous_pose_covariance,
                                    double min_variance) {
  return regularized_increment_covariance(odo.covariance, odo.increment_covariance, odo.planar, delta,
                                          previous_pose_covariance, min_variance);
}

/// The increment covariance the filters predict with: the stated one with its eigenvalues floored at `min_variance`
/// (positive definite, so the prediction keeps the filter's covariance positive definite).
inline Matrix6 filter_increment_covariance(const Odometry& odo, const SE3& delta,
                                           const Matrix6& previous_pose_covariance, double min_variance) {
  return filter::floor_eigenvalues<6>(stated_increment_covariance(odo, delta, previous_pose_covariance), min_variance);
}

}  // namespace sextant::engine
