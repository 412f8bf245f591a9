#pragma once
// The rotation a quaternion read from outside spells, whatever its scale.
#include <Eigen/Geometry>

#include <cmath>
#include <optional>

namespace sextant {

/// The unit quaternion [w, x, y, z] spells: normalized after scaling by its largest component, so that one of 1e300s
/// or of denormals, whose plain norm overflows or underflows, is still the rotation it spells.  Nothing when a
/// component is not finite or all are zero (no rotation).
inline std::optional<Eigen::Quaterniond> unit_quaternion(double w, double x, double y, double z) {
  const Eigen::Vector4d wxyz(w, x, y, z);
  if (!wxyz.allFinite()) return std::nullopt;
  const double scale = wxyz.cwiseAbs().maxCoeff();
  if (!(scale > 0)) return std::nullopt;
  const Eigen::Vector4d u = (wxyz / scale).normalized();
  return Eigen::Quaterniond(u[0], u[1], u[2], u[3]);
}

}  // namespace sextant
