#pragma once
// Covariances of poses under sextant's right perturbation (T = T_hat Exp(xi), xi = [translation; rotation]),
// shared by the stages that compose odometry (Sola et al., "A micro Lie theory", arXiv 1812.01537, eq. 55 and the
// adjoint of eq. 29).
#include "daemon/engine/events.hpp"
#include "estimators/lie/se3.hpp"

#include <Eigen/Eigenvalues>

namespace sextant::engine {

/// Covariance of X Delta given X's covariance P and Delta's covariance Q (independent):
/// Ad(Delta^-1) P Ad(Delta^-1)' + Q, symmetrized.
inline Matrix6 compose_covariance(const Matrix6& P, const SE3& delta, const Matrix6& Q) {
  const Matrix6 ad = delta.inverse().adjoint();
  const Matrix6 out = ad * P * ad.transpose() + Q;
  return 0.5 * (out + out.transpose());
}

/// The nearest positive semi-definite matrix (Higham 1988): symmetrize and clamp negative eigenvalues to zero.
inline Matrix6 nearest_psd(const Matrix6& m) {
  const Matrix6 s = 0.5 * (m + m.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix6> eig(s);
  const Eigen::Matrix<double, 6, 1> ev = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * ev.asDiagonal() * eig.eigenvectors().transpose();
}

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message: its increment covariance when the
/// sender gives one, else the part of its pose covariance that grew since the previous message (robot_localization's
/// differential mode), projected onto the PSD cone; `min_variance` is added to the diagonal entries the source uses
/// (x, y, yaw when planar) so that it stays positive definite.
inline Matrix6 increment_covariance(const Odometry& odo, const SE3& delta, const Matrix6& previous_pose_covariance,
                                    double min_variance) {
  Matrix6 q = odo.increment_covariance
                  ? *odo.increment_covariance
                  : nearest_psd(odo.covariance - compose_covariance(previous_pose_covariance, delta, Matrix6::Zero()));
  if (odo.planar) {
    for (int i : {0, 1, 5}) q(i, i) += min_variance;
  } else {
    q.diagonal().array() += min_variance;
  }
  return q;
}

}  // namespace sextant::engine
