#pragma once
// The passive-sensor measurement model (the passive-association paper's eq. 1-2, see tuple_costs.hpp): a sensor at
// p sees a target at x as
//   azimuth   = atan2(dy, dx)
//   elevation = atan2(dz, rho),   d = x - p,  rho = sqrt(dx^2 + dy^2),  r = |d|
// with Jacobian  d az/dx = [-dy/rho^2, dx/rho^2, 0],  d el/dx = [-dx dz/(r^2 rho), -dy dz/(r^2 rho), rho/r^2].
#include <Eigen/Core>

#include <optional>

namespace sextant::assoc {

/// [azimuth, elevation] of `target` seen from `sensor` (radians); nullopt when the target is on the sensor's
/// vertical (rho ~ 0), where azimuth is undefined.  `J` receives the 2x3 Jacobian with respect to the target.
std::optional<Eigen::Vector2d> bearing(const Eigen::Vector3d& sensor, const Eigen::Vector3d& target,
                                       Eigen::Matrix<double, 2, 3>* J = nullptr);

/// The unit line-of-sight vector of an [azimuth, elevation] pair.
Eigen::Vector3d line_of_sight(double azimuth, double elevation);

}  // namespace sextant::assoc
