#pragma once
// The covariance added to the odometry edge of a keyframe re-anchored after a jump (KeyframeSelector's kReanchored,
// estimators/keyframe/keyframe_selector.hpp): the odometry across the jump is what made it implausible, so the edge
// only says "somewhere around there": each translation axis gets the variance |rho|^2 and each rotation axis |phi|^2,
// mu = Log(edge) = [rho; phi] (planar: x, y and yaw only, from the SE(2) logarithm).  The new segment stays connected
// (one graph, one map frame, the smoother's system stays determined) and starts where the odometry put it, but a loop
// across the jump moves it almost freely, and the loop gate's odometry path covariance (loop_gate.hpp) widens by the
// same amount, so such loops are not refused.
#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/se2.hpp"
#include "estimators/lie/se3.hpp"

namespace sextant::slam {

inline Matrix6d jump_covariance(const SE3& edge, bool planar) {
  if (planar) {
    const Eigen::Vector3d mu = SE2::from_se3(edge).log();
    const double t = mu.head<2>().squaredNorm();
    return embed_planar(Eigen::Vector3d(t, t, mu[2] * mu[2]).asDiagonal().toDenseMatrix());
  }
  const Vector6d mu = edge.log();
  Matrix6d c = Matrix6d::Zero();
  c.topLeftCorner<3, 3>().diagonal().setConstant(mu.head<3>().squaredNorm());
  c.bottomRightCorner<3, 3>().diagonal().setConstant(mu.tail<3>().squaredNorm());
  return c;
}

}  // namespace sextant::slam
