#pragma once
// The odometry covariances the stages compute from an odometry message: the plain-value definitions are in
// estimators/lie/pose_covariance.hpp (compose_covariance, nearest_psd and the increment's, found from here
// unqualified: the engine's namespace is inside sextant's).
#include "daemon/engine/events.hpp"
#include "estimators/lie/pose_covariance.hpp"

namespace sextant::engine {

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message as the sender states it
/// (sextant::stated_increment_covariance).
inline Matrix6 stated_increment_covariance(const Odometry& odo, const SE3& delta,
                                           const Matrix6& previous_pose_covariance) {
  return sextant::stated_increment_covariance(odo.covariance, odo.increment_covariance, delta,
                                              previous_pose_covariance);
}

/// The increment covariance dead reckoning, the graph stage and the 3-D filter compose or predict with
/// (sextant::regularized_increment_covariance: eigenvalues on the body's axes floored at `min_variance`).
inline Matrix6 increment_covariance(const Odometry& odo, const SE3& delta, const Matrix6& previous_pose_covariance,
                                    double min_variance) {
  return regularized_increment_covariance(odo.covariance, odo.increment_covariance, odo.planar, delta,
                                          previous_pose_covariance, min_variance);
}

}  // namespace sextant::engine
