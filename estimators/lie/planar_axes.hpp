#pragma once
// Planar bodies in sextant's 6-D tangent order [x y z | roll pitch yaw]: their three axes are x, y and yaw, rows and
// columns 0, 1 and 5 of a 6x6 covariance or information.  The one home of that mapping.
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

#include <span>

namespace sextant {

inline constexpr int kPlanarAxes[3] = {0, 1, 5};
inline constexpr int kSpatialAxes[6] = {0, 1, 2, 3, 4, 5};

/// The axes a body's poses and covariances use: x, y and yaw when it is planar, all six otherwise.
inline std::span<const int> pose_axes(bool planar) {
  return planar ? std::span<const int>(kPlanarAxes) : std::span<const int>(kSpatialAxes);
}

/// The 3x3 block over (x, y, yaw) of a 6x6 matrix.
inline Eigen::Matrix3d planar_block(const Matrix6d& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = m(kPlanarAxes[r], kPlanarAxes[c]);
  return out;
}

/// A 3x3 matrix over (x, y, yaw) placed in a 6x6 one, zero elsewhere.
inline Matrix6d embed_planar(const Eigen::Matrix3d& m3) {
  Matrix6d out = Matrix6d::Zero();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(kPlanarAxes[r], kPlanarAxes[c]) = m3(r, c);
  return out;
}

}  // namespace sextant
