#pragma once
// Target position from the bearings of two or more passive sensors.
//  1. Linear least squares (the passive-association paper's eq. 9-12, see tuple_costs.hpp): each sensor gives two
//     equations linear in x,
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
  Eigen::Vector3d sensor = Eigen::Vector3d::Zero();          // sensor position, metres
  double azimuth = 0, elevation = 0;                         // radians
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();  // over [azimuth, elevation]
};

struct Triangulation {
  bool valid = false;
  std::string reason;  // why not valid: "fewer than 2 sensors", "ill-conditioned geometry", ...
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
  double residual = 0;   // sum nu' R^-1 nu at the estimate (chi-square with 2S - 3 dof)
  double condition = 0;  // condition number of the information matrix
};

/// The Gauss-Newton normal equations of sum nu' R^-1 nu linearized at a position x: information = sum J' R^-1 J,
/// gradient = sum J' R^-1 nu (the step toward the minimum is information^-1 gradient), residual = sum nu' R^-1 nu,
/// with nu = [wrapped azimuth, elevation] measured minus predicted at x.
struct NormalEquations {
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  double residual = 0;
};

/// An observation prepared for linearizing it many times (the tuple builder): what depends on the measurement
/// alone is computed once.
struct PreparedBearing {
  Eigen::Vector3d sensor = Eigen::Vector3d::Zero();
  double sin_azimuth = 0, cos_azimuth = 1, sin_elevation = 0, cos_elevation = 1;
  Eigen::Matrix2d information = Eigen::Matrix2d::Identity();     // R^-1
  Eigen::Matrix3d linear_information = Eigen::Matrix3d::Zero();  // H'H of its two rows of step 1
  Eigen::Vector3d linear_rhs = Eigen::Vector3d::Zero();          // H'Y of its two rows

  PreparedBearing() = default;
  /// `inverse_covariance` = R^-1 (given so callers can compute it once).
  PreparedBearing(const BearingObservation& o, const Eigen::Matrix2d& inverse_covariance);
};

/// Adds the prepared observation `o` linearized at `x` to `n`.  False, leaving `n` unchanged, when x is on the
/// sensor's vertical (azimuth undefined).  The residual angles are taken as the angles between measured and
/// predicted direction, atan2(sin(z - h), cos(z - h)) with sin and cos from the products of their sines and
/// cosines (already wrapped; no atan2 of the predicted angles themselves).
bool add_observation(NormalEquations& n, const PreparedBearing& o, const Eigen::Vector3d& x);

/// The same for a plain observation (prepares it first).
bool add_observation(NormalEquations& n, const BearingObservation& o, const Eigen::Matrix2d& inverse_covariance,
                     const Eigen::Vector3d& x);

/// Step 3 at a final position: `valid` when x and the covariance information^-1 are finite and the information's
/// condition number is below `max_condition`; residual from `n`.
Triangulation triangulation_at(const Eigen::Vector3d& x, const NormalEquations& n, double max_condition = 1e10);

/// The linear least-squares position alone (step 1).
Triangulation triangulate_linear(const std::vector<BearingObservation>& obs);

/// Step 1 from the summed linear normal equations H'H x = H'Y of two or more observations (PreparedBearing's
/// linear_information and linear_rhs added up).
Triangulation triangulate_linear(const Eigen::Matrix3d& linear_information, const Eigen::Vector3d& linear_rhs);

/// Steps 1-3.  `max_condition` bounds the information matrix's condition number.
Triangulation triangulate(const std::vector<BearingObservation>& obs, int gauss_newton_steps = 3,
                          double max_condition = 1e10);

}  // namespace sextant::assoc
