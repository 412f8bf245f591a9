#pragma once
// Moving an inertial estimator's state into East-North-Up once its frame's heading is known
// (gnss_heading.hpp: enu = Rz(yaw) track + t, horizontal).  The whole state turns about Up and shifts rigidly:
//   p' = Rz p + t,   v' = Rz v,   R' = Rz R   (biases are in body axes: unchanged).
// The filter's covariance (error state [dp, dv, dth, db_a, db_g], dth on the right) goes through the same rotation,
// its horizontal position is replaced by the alignment's, and the alignment's own uncertainty (its centroid c per
// axis and its yaw psi) enters through G = d(dx) / d(c, psi):
//   dp_xy = dc + dpsi ez x (p' - c'),   dv = dpsi ez x v',   dth = dpsi R'^T ez
// (a world-frame rotation dpsi about Up is the body-frame rotation R'^T ez dpsi), so P' = J P J^T + G S G^T with
// S = diag(c_var, c_var, yaw_sigma^2).
#include "estimators/inertial/error_state_ekf.hpp"
#include "estimators/inertial/gnss_heading.hpp"
#include "estimators/inertial/imu_preintegration.hpp"

namespace sextant::inertial {

/// Rz(yaw) as a 3-D rotation about Up.
Eigen::Matrix3d yaw_rotation(const PlanarAlignment& a);
/// The filter's state in ENU.
EskfState realigned(const PlanarAlignment& a, const EskfState& x);
/// Its covariance in ENU (see the file comment); `x` the state before realigning.
ErrorStateEkf::Matrix15 realigned_covariance(const PlanarAlignment& a, const EskfState& x,
                                             const ErrorStateEkf::Matrix15& P);
/// A navigation state (the smoother's) in ENU.
NavState realigned(const PlanarAlignment& a, const NavState& x);

}  // namespace sextant::inertial
