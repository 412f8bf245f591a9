#pragma once
// Covariances of poses under sextant's right perturbation (T = T_hat Exp(xi), xi = [translation; rotation]),
// shared by the stages that compose odometry (Sola et al., "A micro Lie theory", arXiv 1812.01537, eq. 55 and the
// adjoint of eq. 29).
#include "daemon/engine/events.hpp"
#include "estimators/filter/eigenvalue_floor.hpp"
#include "estimators/lie/se3.hpp"

namespace sextant::engine {

/// Covariance of X Delta given X's covariance P and Delta's covariance Q (independent):
/// Ad(Delta^-1) P Ad(Delta^-1)' + Q, symmetrized.
inline Matrix6 compose_covariance(const Matrix6& P, const SE3& delta, const Matrix6& Q) {
  const Matrix6 ad = delta.inverse().adjoint();
  const Matrix6 out = ad * P * ad.transpose() + Q;
  return 0.5 * (out + out.transpose());
}

/// The nearest positive semi-definite matrix (Higham 1988): eigenvalues floored at zero (eigenvalue_floor.hpp).
inline Matrix6 nearest_psd(const Matrix6& m) { return filter::floor_eigenvalues<6>(m, 0.0); }

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message as the sender states it: its increment
/// covariance when it gives one, else the part of its pose covariance that grew since the previous message
/// (robot_localization's differential mode), which numerical noise or a reset can leave indefinite.  Unregularized:
/// each user regularizes it as below.
inline Matrix6 stated_increment_covariance(const Odometry& odo, const SE3& delta,
                                           const Matrix6& previous_pose_covariance) {
  return odo.increment_covariance ? *odo.increment_covariance
                                  : Matrix6(odo.covariance - compose_covariance(previous_pose_covariance, delta,
                                                                                Matrix6::Zero()));
}

/// The increment covariance dead reckoning and the graph stage compose: the stated one, the
/// differential growth projected onto the PSD cone, and `min_variance` added to the diagonal entries the source uses
/// (x, y, yaw when planar) so that it stays positive definite.  The filters floor the eigenvalues at `min_variance`
/// instead (filter_increment_covariance): where the stated covariance is positive definite with eigenvalues above
/// `min_variance` the two differ only by the `min_variance` added here to the diagonal.
inline Matrix6 increment_covariance(const Odometry& odo, const SE3& delta, const Matrix6& previous_pose_covariance,
                                    double min_variance) {
  Matrix6 q = stated_increment_covariance(odo, delta, previous_pose_covariance);
  if (!odo.increment_covariance) q = nearest_psd(q);
  if (odo.planar) {
    for (int i : {0, 1, 5}) q(i, i) += min_variance;
  } else {
    q.diagonal().array() += min_variance;
  }
  return q;
}

/// The increment covariance the filters predict with: the stated one with its eigenvalues floored at `min_variance`
/// (positive definite, so the prediction keeps the filter's covariance positive definite).
inline Matrix6 filter_increment_covariance(const Odometry& odo, const SE3& delta,
                                           const Matrix6& previous_pose_covariance, double min_variance) {
  return filter::floor_eigenvalues<6>(stated_increment_covariance(odo, delta, previous_pose_covariance), min_variance);
}

}  // namespace sextant::engine
