#pragma once
// Covariances of poses under sextant's right perturbation (T = T_hat Exp(xi), xi = [translation; rotation]):
// composition along a chain of motions and the covariance of one odometry increment (Sola et al., "A micro Lie
// theory", arXiv 1812.01537, eq. 55 and the adjoint of eq. 29).  Plain values here; the engine's wrappers that take
// an odometry message are in daemon/engine/pose_covariance.hpp.
//
// The increment covariance a sender states, or the growth of its pose covariance, can be indefinite (rounding, a
// reset, a malformed message).  Each user regularizes it in the way its use needs:
//  - dead reckoning (daemon/engine/dead_reckoning_stage.cpp) and the SLAM layer's odometry edges
//    (estimators/slam/slam_graph.cpp): regularized_increment_covariance below.  A differential growth is projected
//    onto the PSD cone (nearest_psd), a stated increment is kept as stated, and min_variance is added to the diagonal
//    of the axes the body uses.  Composing a PSD increment keeps the chain's covariance PSD and min_variance keeps a
//    step without growth invertible; a stated increment that is indefinite stays so, and the SLAM layer then refuses
//    the edge (slam/pose_factors.hpp, odometry_factor) rather than trust a repaired, over-confident one.
//  - the filters' predictions: the 3-D EKF (daemon/engine/pose_covariance.hpp, filter_increment_covariance) and the
//    particle filter (daemon/engine/planar_pose_covariance.hpp, planar_increment_covariance) floor the eigenvalues of
//    stated_increment_covariance at min_variance (filter/eigenvalue_floor.hpp): a prediction must keep the filter's
//    covariance positive definite whatever the sender says, and a filter has no edge to refuse.
//  - the planar EKF (estimators/filter/multi_source_ekf.cpp, increment_noise): the same eigenvalue floor, on the
//    (x, y, yaw) covariances of its planar messages with the SE(2) adjoint.  It does not call this header: the SE(3)
//    form reaches the same value with other roundings (a delta through quaternions, a symmetrized composition), so
//    routing it here would change its numbers.
//  - the graph's fused pose (daemon/engine/graph_pose_stage.cpp): pose_covariance_growth since the newest keyframe,
//    projected onto the PSD cone without a floor, composed onto the keyframe's marginal covariance: that marginal is
//    positive definite already, and a floor added at every odometry message would inflate what is published.
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
inline Matrix6d stated_increment_covariance(const Matrix6d& pose_covariance, const std::optional<Matrix6d>& stated_increment,
                                            const SE3& delta, const Matrix6d& previous_pose_covariance) {
  return stated_increment ? *stated_increment : pose_covariance_growth(pose_covariance, delta, previous_pose_covariance);
}

/// The increment covariance dead reckoning and the SLAM layer compose: the stated one, the differential growth
/// projected onto the PSD cone, and `min_variance` added to the diagonal entries the source uses (x, y, yaw when
/// planar) so that it stays positive definite.  The filters floor the eigenvalues at `min_variance` instead (see
/// above): where the stated covariance is positive definite with eigenvalues above `min_variance` the two differ
/// only by the `min_variance` added here to the diagonal.
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
