#include "estimators/lie/so3.hpp"

#include <cmath>

namespace sextant {

Eigen::Matrix3d SO3::hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

SO3 SO3::exp(const Eigen::Vector3d& w, Eigen::Matrix3d* J_right) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  Eigen::Quaterniond q;
  if (t < 1e-8) {
    // Taylor: cos(t/2) ~ 1 - t^2/8, sin(t/2)/t ~ 1/2 - t^2/48.
    q.w() = 1 - t2 / 8;
    q.vec() = (0.5 - t2 / 48) * w;
  } else {
    q.w() = std::cos(t / 2);
    q.vec() = std::sin(t / 2) / t * w;
  }
  if (J_right) *J_right = right_jacobian(w);
  SO3 r;
  r.q_ = q.normalized();
  return r;
}

Eigen::Vector3d SO3::log(Eigen::Matrix3d* J_right_inv) const {
  // Use the hemisphere w >= 0 so the angle is in [0, pi].
  Eigen::Quaterniond q = q_;
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double n = q.vec().norm();
  Eigen::Vector3d w;
  if (n < 1e-8) {
    // t = 2 atan2(n, qw) ~ 2 n / qw (1 - n^2 / (3 qw^2)).
    w = 2.0 / q.w() * (1 - n * n / (3 * q.w() * q.w())) * q.vec();
  } else {
    w = 2 * std::atan2(n, q.w()) / n * q.vec();
  }
  if (J_right_inv) *J_right_inv = right_jacobian_inverse(w);
  return w;
}

Eigen::Matrix3d SO3::right_jacobian(const Eigen::Vector3d& w) {
  const double t2 = w.squaredNorm();
  const Eigen::Matrix3d W = hat(w);
  // Series below 1e-3 rad, where (t - sin t)/t^3 loses every digit to cancellation.
  if (t2 < 1e-6) return Eigen::Matrix3d::Identity() - (0.5 - t2 / 24) * W + (1.0 / 6 - t2 / 120) * W * W;
  const double t = std::sqrt(t2);
  return Eigen::Matrix3d::Identity() - (1 - std::cos(t)) / t2 * W + (t - std::sin(t)) / (t2 * t) * W * W;
}

Eigen::Matrix3d SO3::right_jacobian_inverse(const Eigen::Vector3d& w) {
  const double t2 = w.squaredNorm();
  const Eigen::Matrix3d W = hat(w);
  if (t2 < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / 12 + t2 / 720) * W * W;
  const double t = std::sqrt(t2);
  return Eigen::Matrix3d::Identity() + 0.5 * W + (1 / t2 - (1 + std::cos(t)) / (2 * t * std::sin(t))) * W * W;
}

}  // namespace sextant
