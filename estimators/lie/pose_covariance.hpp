#pragma once
// Covariances of poses under sextant's right perturbation (T = T_hat Exp(xi), xi = [translation; rotation]):
// composition along a chain of motions and the covariance of one odometry increment (Sola et al., "A micro Lie
// theory", arXiv 1812.01537, eq. 55 and the adjoint of eq. 29).  Plain values here; the engine's wrappers that take
// an odometry message are in daemon/engine/pose_covariance.hpp.
#include "estimators/filter/eigenvalue_floor.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se3.hpp"

#include <optional>

namespace sextant {

/// Covariance of X Delta given X's covariance P and Delta's covariance Q (independent):
/// Ad(Delta^-1) P Ad(Delta^-1)' + Q, symmetrized.
inline Matrix6d compose_covariance(const Matrix6d& P, const SE3& delta, const Matrix6d& Q) {
  const Matrix6d ad = delta.inverse().adjoint();
  const Matrix6d out = ad * P * ad.transpose() + Q;
  return 0.5 * (out + out.transpose());
}

/// The nearest positive semi-definite matrix (Higham 1988): eigenvalues floored at zero (eigenvalue_floor.hpp).
inline Matrix6d nearest_psd(const Matrix6d& m) { return filter::floor_eigenvalues<6>(m, 0.0); }

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message as the sender states it: its increment
/// covariance when it gives one (`stated_increment`), else the part of its pose covariance that grew since the
/// previous message (robot_localization's differential mode), which numerical noise or a reset can leave
/// indefinite.  Unregularized: each user regularizes it as below.
inline Matrix6d stated_increment_covariance(const Matrix6d& pose_covariance, const std::optional<Matrix6d>& stated_increment,
                                            const SE3& delta, const Matrix6d& previous_pose_covariance) {
  return stated_increment ? *stated_increment
                          : Matrix6d(pose_covariance - compose_covariance(previous_pose_covariance, delta, Matrix6d::Zero()));
}

/// The increment covariance dead reckoning and the SLAM layer compose: the stated one, the differential growth
/// projected onto the PSD cone, and `min_variance` added to the diagonal entries the source uses (x, y, yaw when
/// planar) so that it stays positive definite.  The filters floor the eigenvalues at `min_variance` instead
/// (daemon/engine/pose_covariance.hpp, filter_increment_covariance): where the stated covariance is positive definite
/// with eigenvalues above `min_variance` the two differ only by the `min_variance` added here to the diagonal.
inline Matrix6d regularized_increment_covariance(const Matrix6d& pose_covariance,
                                                 const std::optional<Matrix6d>& stated_increment, bool planar,
                                                 const SE3& delta, const Matrix6d& previous_pose_covariance,
                                                 double min_variance) {
  Matrix6d q = stated_increment_covariance(pose_covariance, stated_increment, delta, previous_pose_covariance);
  if (!stated_increment) q = nearest_psd(q);
  for (int i : pose_axes(planar)) q(i, i) += min_variance;
  return q;
}

}  // namespace sextant
