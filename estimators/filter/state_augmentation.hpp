#pragma once
// EKF-SLAM state augmentation (Thrun, Burgard & Fox, Probabilistic Robotics, §10.2; Bailey & Durrant-Whyte,
// "SLAM: Part I", 2006): a new landmark l = g(x_r, z), a function of the robot block x_r (the first k entries of
// the state) and of a sighting z ~ N(z, R) independent of the state, is appended to the state.  Linearized with
// Jx = dg/dx_r (m x k) and Jz = dg/dz (m x m), the covariance of [x; l] is
//     [ P        P_r: ' Jx' ]
//     [ Jx P_r:  Jx P_rr Jx' + Jz R Jz' ]
// with P_r: the robot's k rows of P and P_rr its k x k block; the new diagonal block is symmetrized.  O(n k m).
#include <Eigen/Core>

namespace sextant::filter {

/// P grown by the landmark's m rows and columns, as above.  `Jx` is m x k (k <= P.rows()), `Jz` and `R` m x m.
Eigen::MatrixXd augmented_covariance(const Eigen::MatrixXd& P, const Eigen::MatrixXd& Jx, const Eigen::MatrixXd& Jz,
                                     const Eigen::MatrixXd& R);

}  // namespace sextant::filter
