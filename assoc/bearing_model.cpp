#include "assoc/bearing_model.hpp"

#include <cmath>

namespace sextant::assoc {

std::optional<Eigen::Vector2d> bearing(const Eigen::Vector3d& sensor, const Eigen::Vector3d& target,
                                       Eigen::Matrix<double, 2, 3>* J) {
  const Eigen::Vector3d d = target - sensor;
  const double rho2 = d.x() * d.x() + d.y() * d.y(), rho = std::sqrt(rho2), r2 = d.squaredNorm();
  if (rho < 1e-9 * std::max(1.0, std::sqrt(r2))) return std::nullopt;
  if (J) {
    *J << -d.y() / rho2, d.x() / rho2, 0, -d.x() * d.z() / (r2 * rho), -d.y() * d.z() / (r2 * rho), rho / r2;
  }
  return Eigen::Vector2d(std::atan2(d.y(), d.x()), std::atan2(d.z(), rho));
}

Eigen::Vector3d line_of_sight(double az, double el) {
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

}  // namespace sextant::assoc
