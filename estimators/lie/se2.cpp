#include "estimators/lie/se2.hpp"

namespace sextant {
namespace {

// V(theta) of eq. 158: sin(t)/t and (1 - cos t)/t, by series below 1e-4 rad where the closed forms cancel.
void v_coefficients(double t, double& a, double& b) {
  if (std::abs(t) < 1e-4) {
    const double t2 = t * t;
    a = 1 - t2 / 6 + t2 * t2 / 120;
    b = t / 2 - t * t2 / 24 + t * t2 * t2 / 720;
  } else {
    a = std::sin(t) / t;
    b = (1 - std::cos(t)) / t;
  }
}

}  // namespace

SE2 SE2::exp(const Eigen::Vector3d& tau, Eigen::Matrix3d* J_right) {
  double a, b;
  v_coefficients(tau.z(), a, b);
  Eigen::Matrix2d V;
  V << a, -b, b, a;
  if (J_right) *J_right = right_jacobian(tau);
  return SE2(SO2(tau.z()), V * tau.head<2>());
}

Eigen::Vector3d SE2::log(Eigen::Matrix3d* J_right_inv) const {
  const double t = R_.angle();
  double a, b;
  v_coefficients(t, a, b);
  Eigen::Matrix2d V;
  V << a, -b, b, a;
  Eigen::Vector3d tau;
  tau << V.inverse() * t_, t;
  if (J_right_inv) *J_right_inv = right_jacobian(tau).inverse();
  return tau;
}

SE2 SE2::inverse(Eigen::Matrix3d* J) const {
  if (J) *J = -adjoint();
  const SO2 Ri = R_.inverse();
  return SE2(Ri, -(Ri * t_));
}

SE2 SE2::compose(const SE2& b, Eigen::Matrix3d* J_this, Eigen::Matrix3d* J_b) const {
  if (J_this) *J_this = b.inverse().adjoint();
  if (J_b) J_b->setIdentity();
  return *this * b;
}

SE2 SE2::between(const SE2& b, Eigen::Matrix3d* J_this, Eigen::Matrix3d* J_b) const {
  const SE2 d = inverse() * b;
  if (J_this) *J_this = -d.inverse().adjoint();
  if (J_b) J_b->setIdentity();
  return d;
}

Eigen::Vector2d SE2::act(const Eigen::Vector2d& p, Eigen::Matrix<double, 2, 3>* J_this, Eigen::Matrix2d* J_p) const {
  const Eigen::Matrix2d R = R_.matrix();
  if (J_this) {
    J_this->leftCols<2>() = R;
    J_this->col(2) = R * Eigen::Vector2d(-p.y(), p.x());
  }
  if (J_p) *J_p = R;
  return R * p + t_;
}

Eigen::Matrix3d SE2::adjoint() const {
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  A.topLeftCorner<2, 2>() = R_.matrix();
  A(0, 2) = t_.y();
  A(1, 2) = -t_.x();
  return A;
}

Eigen::Matrix3d SE2::right_jacobian(const Eigen::Vector3d& tau) {
  const double t = tau.z(), r1 = tau.x(), r2 = tau.y();
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  if (std::abs(t) < 1e-4) {
    // Series of eq. 163 to second order in t (the closed form cancels catastrophically here).
    J(0, 0) = 1 - t * t / 6, J(0, 1) = t / 2, J(0, 2) = -r2 / 2 + t * r1 / 6;
    J(1, 0) = -t / 2, J(1, 1) = 1 - t * t / 6, J(1, 2) = r1 / 2 + t * r2 / 6;
    return J;
  }
  const double s = std::sin(t), c = std::cos(t);
  J(0, 0) = s / t, J(0, 1) = (1 - c) / t, J(0, 2) = (t * r1 - r2 + r2 * c - r1 * s) / (t * t);
  J(1, 0) = (c - 1) / t, J(1, 1) = s / t, J(1, 2) = (r1 + t * r2 - r1 * c - r2 * s) / (t * t);
  return J;
}

SE3 SE2::to_se3() const { return SE3(SO3::exp(Eigen::Vector3d(0, 0, R_.angle())), Eigen::Vector3d(t_.x(), t_.y(), 0)); }

SE2 SE2::from_se3(const SE3& x) {
  const Eigen::Matrix3d R = x.rotation().matrix();
  return SE2(x.translation().x(), x.translation().y(), std::atan2(R(1, 0), R(0, 0)));
}

}  // namespace sextant
