#pragma once
// Covariances of poses under sextant's right perturbation (T = T_hat Exp(xi), xi = [translation; rotation]):
// composition along a chain of motions and the covariance of one odometry increment (Sola et al., "A micro Lie
// theory", arXiv 1812.01537, eq. 55 and the adjoint of eq. 29).  Plain values here; the engine's wrappers that take
// an odometry message are in daemon/engine/pose_covariance.hpp.
//
// The increment covariance a sender states has passed the intake's positive-definiteness check (spd_matrix.hpp's
// rule: a stated covariance that is not positive definite is bad input); the growth of a pose covariance between two
// messages is derived and can be indefinite (rounding, a reset of the sender).  Every estimator regularizes the
// increment in the same one way, regularized_increment_covariance below: the eigenvalues of its block on the body's
// axes floored at min_variance (spd_matrix.hpp, floor_eigenvalues), so that composing or predicting with it keeps a
// covariance positive definite and a step without growth invertible.  Its users: dead reckoning
// (daemon/engine/dead_reckoning_stage.cpp), the SLAM layer's odometry edges (estimators/slam/slam_graph.cpp), the
// 3-D EKF's prediction (daemon/engine/filter_stage.cpp), the particle filter's (its (x, y, yaw) block,
// daemon/engine/planar_pose_covariance.hpp) and the planar EKF's (estimators/filter/multi_source_ekf.cpp,
// increment_noise: the same floor on the (x, y, yaw) covariances of its planar messages with the SE(2) adjoint).
// The graph's fused pose (daemon/engine/graph_pose_stage.cpp) floors its pose_covariance_growth at 0 (nearest_psd):
// it is composed onto the keyframe's marginal covariance, positive definite already, and a floor added at every
// odometry message would inflate what is published.
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se3.hpp"
#include "estimators/spd_matrix.hpp"

#include <optional>

namespace sextant {

/// Covariance of X Delta given X's covariance P and Delta's covariance Q (independent):
/// Ad(Delta^-1) P Ad(Delta^-1)' + Q, symmetrized.
inline Matrix6d compose_covariance(const Matrix6d& P, const SE3& delta, const Matrix6d& Q) {
  const Matrix6d ad = delta.inverse().adjoint();
  return symmetrized(Matrix6d(ad * P * ad.transpose() + Q));
}

/// The nearest positive semi-definite matrix (Higham 1988): eigenvalues floored at zero (spd_matrix.hpp).
inline Matrix6d nearest_psd(const Matrix6d& m) { return floor_eigenvalues(m, 0.0); }

/// The part of a pose covariance P that grew over the motion Delta since a pose with covariance P_prev:
/// P - Ad(Delta^-1) P_prev Ad(Delta^-1)' (robot_localization's differential mode).  Numerical noise or a reset can
/// leave it indefinite; unregularized (see above).
inline Matrix6d pose_covariance_growth(const Matrix6d& pose_covariance, const SE3& delta,
                                       const Matrix6d& previous_pose_covariance) {
  return pose_covariance - compose_covariance(previous_pose_covariance, delta, Matrix6d::Zero());
}

/// The covariance of the motion Delta = T_prev^-1 T of an odometry message as the sender states it: its increment
/// covariance when it gives one (`stated_increment`), else the growth of its pose covariance since the previous
/// message.  Unregularized: each user regularizes it as above.
inline Matrix6d stated_increment_covariance(const Matrix6d& pose_covariance,
                                            const std::optional<Matrix6d>& stated_increment, const SE3& delta,
                                            const Matrix6d& previous_pose_covariance) {
  return stated_increment ? *stated_increment
                          : pose_covariance_growth(pose_covariance, delta, previous_pose_covariance);
}

/// The increment covariance every estimator composes or predicts with (see above): the stated one, or the
/// differential growth, with the eigenvalues of its block on the axes the body uses (x, y, yaw when planar, all six
/// otherwise) floored at `min_variance`; the other entries as stated.
inline Matrix6d regularized_increment_covariance(const Matrix6d& pose_covariance,
                                                 const std::optional<Matrix6d>& stated_increment, bool planar,
                                                 const SE3& delta, const Matrix6d& previous_pose_covariance,
                                                 double min_variance) {
  Matrix6d q = stated_increment_covariance(pose_covariance, stated_increment, delta, previous_pose_covariance);
  if (!planar) return floor_eigenvalues(q, min_variance);
  const Eigen::Matrix3d floored = floor_eigenvalues(planar_block(q), min_variance);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) q(kPlanarAxes[r], kPlanarAxes[c]) = floored(r, c);
  return q;
}

/// An error-state filter's pose covariance, over [position error in the world frame; rotation error in the body]
/// (p = p_hat + dp, R = R_hat Exp(theta)), as sextant's right perturbation [rho; theta]: T_hat Exp(xi) moves the
/// position by R_hat rho to first order, so rho = R_hat' dp and the covariance is J P J', J = blockdiag(R_hat', I).
inline Matrix6d right_perturbation_from_world_position(const Eigen::Matrix3d& R_hat,
                                                       const Matrix6d& world_position_body_rotation) {
  Matrix6d J = Matrix6d::Identity();
  J.topLeftCorner<3, 3>() = R_hat.transpose();
  return symmetrized(Matrix6d(J * world_position_body_rotation * J.transpose()));
}

}  // namespace sextant
