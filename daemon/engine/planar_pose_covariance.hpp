#pragma once
// The covariance a planar filter publishes in a FusedPose.  Planar filters (EKF, particle filter) estimate
// (x, y, theta) in the map frame with a covariance P over those global coordinates; sextant's convention
// (events.hpp, DESIGN.md) is a 6x6 covariance over the right perturbation [dx dy dz | rx ry rz] in the body frame.
// For SE(2), T = T_hat * Exp(delta_body) gives, to first order, delta_global = blockdiag(R(theta), 1) delta_body, so
//   delta_body = J delta_global,  J = blockdiag(R(theta)^T, 1),  P_body = J P J^T,
// placed on the x, y and yaw rows/columns (0, 1, 5); z, roll and pitch are left at zero.
#include "daemon/engine/events.hpp"
#include "estimators/lie/se2.hpp"

namespace sextant::engine {

inline Matrix6 planar_covariance_in_body_frame(const SE2& pose, const Eigen::Matrix3d& global_xy_theta) {
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = pose.rotation().matrix().transpose();
  const Eigen::Matrix3d Pb = J * global_xy_theta * J.transpose();
  Matrix6 out = Matrix6::Zero();
  const int idx[3] = {0, 1, 5};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(idx[r], idx[c]) = Pb(r, c);
  return out;
}

}  // namespace sextant::engine
