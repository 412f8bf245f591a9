#pragma once
// Target position from the bearings of two or more passive sensors (assoc.md §1.2).
//  1. Linear least squares (source C eq. 9-12): each sensor gives two equations linear in x,
//       sin(az) x - cos(az) y = sin(az) xs - cos(az) ys
//       cos(az) sin(el) x + sin(az) sin(el) y - cos(el) z = cos(az) sin(el) xs + sin(az) sin(el) ys - cos(el) zs
//     stacked as H x = Y and solved, x = (H'H)^-1 H'Y.
//  2. Gauss-Newton refinement of sum nu' R^-1 nu (maximum likelihood), a few steps.
//  3. Covariance P = (sum J_s' R_s^-1 J_s)^-1 at the estimate (first order; the paper's eq. 13 propagates the
//     noise through the linear system instead, which ignores that H depends on the measurements too).
// Degenerate geometry (near-parallel lines of sight, a target on a sensor's vertical, fewer than 2 sensors) is
// reported as such: `valid` false with a reason, and no NaN reaches the caller.
#include <Eigen/Core>

#include <string>
#include <vector>

namespace sextant::assoc {

struct BearingObservation {
  Eigen::Vector3d sensor = Eigen::Vector3d::Zero();  // sensor position, metres
  double azimuth = 0, elevation = 0;                 // radians
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  // over [azimuth, elevation]
};

struct Triangulation {
  bool valid = false;
  std::string reason;  // why not valid: "fewer than 2 sensors", "ill-conditioned geometry", ...
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double residual = 0;  // sum nu' R^-1 nu at the estimate (chi-square with 2S - 3 dof)
  double condition = 0; // condition number of the information matrix
};

/// The linear least-squares position alone (step 1).
Triangulation triangulate_linear(const std::vector<BearingObservation>& obs);

/// Steps 1-3.  `max_condition` bounds the information matrix's condition number.
Triangulation triangulate(const std::vector<BearingObservation>& obs, int gauss_newton_steps = 3,
                          double max_condition = 1e10);

}  // namespace sextant::assoc
