#pragma once
// Values the tests of pose covariances and pose factors share: tangent vectors, poses from them, SPD matrices, a norm.
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

#include <cmath>

namespace sextant::test {

inline Vector6d tangent(double x, double y, double z, double rx, double ry, double rz) {
  Vector6d xi;
  xi << x, y, z, rx, ry, rz;
  return xi;
}

/// Exp([x y z | rx ry rz]).
inline SE3 pose(double x, double y, double z, double rx, double ry, double rz) {
  return SE3::exp(tangent(x, y, z, rx, ry, rz));
}

/// A fixed symmetric positive definite matrix of entries about `scale`^2, different for each seed.
inline Matrix6d spd(int seed, double scale = 1.0) {
  Matrix6d a;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) a(r, c) = scale * std::sin(1.0 + seed + 7 * r + 3 * c);
  return a * a.transpose() + 0.1 * scale * scale * Matrix6d::Identity();
}

inline double max_abs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

}  // namespace sextant::test
