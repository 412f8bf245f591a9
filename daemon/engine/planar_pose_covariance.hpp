#pragma once
// The covariance a planar filter publishes in a FusedPose.  Planar filters (EKF, particle filter) estimate
// (x, y, theta) in the map frame with a covariance P over those global coordinates; sextant's convention
// (events.hpp) is a 6x6 covariance over the right perturbation [dx dy dz | rx ry rz] in the body frame.
// For SE(2), T = T_hat * Exp(delta_body) gives, to first order, delta_global = blockdiag(R(theta), 1) delta_body, so
//   delta_body = J delta_global,  J = blockdiag(R(theta)^T, 1),  P_body = J P J^T,
// placed on the x, y and yaw rows/columns (0, 1, 5); z, roll and pitch are left at zero.
// Also the other direction, for a planar filter's motion noise: the 3x3 increment covariance of an odometry message.
#include "daemon/engine/events.hpp"
#include "daemon/engine/pose_covariance.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"

namespace sextant::engine {

inline Matrix6 planar_covariance_in_body_frame(const SE2& pose, const Eigen::Matrix3d& global_xy_theta) {
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = pose.rotation().matrix().transpose();
  return embed_planar(Eigen::Matrix3d(J * global_xy_theta * J.transpose()));
}

/// The covariance Q (3x3 over [dx, dy, dtheta], body frame after the motion) of the planar increment `delta` that
/// odometry message `o` brings after a message with pose covariance `previous_covariance`: the (x, y, yaw) block of
/// the one regularized increment covariance (pose_covariance.hpp: the message's increment covariance, or the growth
/// of its pose covariance, with eigenvalues floored at `min_variance`), so the filter's prediction stays positive
/// definite.
inline Eigen::Matrix3d planar_increment_covariance(const Odometry& o, const Matrix6& previous_covariance,
                                                   const SE2& delta, double min_variance) {
  return planar_block(regularized_increment_covariance(o.covariance, o.increment_covariance, /*planar=*/true,
                                                       delta.to_se3(), previous_covariance, min_variance));
}

}  // namespace sextant::engine
