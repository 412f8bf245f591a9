#include "estimators/lie/se3.hpp"

#include <cmath>

namespace sextant {
namespace {

// The Q matrix of the left Jacobian of SE(3): Jl(xi) = [Jl(phi), Q(rho, phi); 0, Jl(phi)]
// (Barfoot & Furgale, "Associating uncertainty with three-dimensional poses", T-RO 2014, eq. 102).
Eigen::Matrix3d barfoot_q(const Eigen::Vector3d& rho, const Eigen::Vector3d& phi) {
  const Eigen::Matrix3d P = SO3::hat(phi), R = SO3::hat(rho);
  const double t2 = phi.squaredNorm();
  double a, b, c;
  if (t2 < 1e-4) {  // series of the three coefficients below (their closed forms cancel for small angles)
    a = 1.0 / 6 - t2 / 120 + t2 * t2 / 5040;
    b = 1.0 / 24 - t2 / 720 + t2 * t2 / 40320;
    c = 1.0 / 120 - t2 / 2520 + t2 * t2 / 120960;
  } else {
    const double t = std::sqrt(t2), s = std::sin(t), co = std::cos(t);
    a = (t - s) / (t2 * t);
    b = (t2 + 2 * co - 2) / (2 * t2 * t2);
    c = (2 * t - 3 * s + t * co) / (2 * t2 * t2 * t);
  }
  return 0.5 * R + a * (P * R + R * P + P * R * P) + b * (P * P * R + R * P * P - 3 * P * R * P) +
         c * (P * R * P * P + P * P * R * P);
}

}  // namespace

SE3 SE3::exp(const Vector6& xi, Matrix6* J_right) {
  const Eigen::Vector3d rho = xi.head<3>(), phi = xi.tail<3>();
  if (J_right) *J_right = right_jacobian(xi);
  return SE3(SO3::exp(phi), SO3::left_jacobian(phi) * rho);
}

SE3::Vector6 SE3::log(Matrix6* J_right_inv) const {
  const Eigen::Vector3d phi = R_.log();
  // Jl(phi)^-1 = Jr(-phi)^-1 = Jr^-1(-phi).
  Vector6 xi;
  xi << SO3::right_jacobian_inverse(-phi) * t_, phi;
  if (J_right_inv) *J_right_inv = right_jacobian_inverse(xi);
  return xi;
}

SE3 SE3::inverse(Matrix6* J) const {
  if (J) *J = -adjoint();
  const SO3 Ri = R_.inverse();
  return SE3(Ri, -(Ri * t_));
}

SE3 SE3::compose(const SE3& b, Matrix6* J_this, Matrix6* J_b) const {
  if (J_this) *J_this = b.inverse().adjoint();
  if (J_b) J_b->setIdentity();
  return *this * b;
}

SE3 SE3::between(const SE3& b, Matrix6* J_this, Matrix6* J_b) const {
  const SE3 d = inverse() * b;
  if (J_this) *J_this = -d.inverse().adjoint();
  if (J_b) J_b->setIdentity();
  return d;
}

Eigen::Vector3d SE3::act(const Eigen::Vector3d& p, Eigen::Matrix<double, 3, 6>* J_this, Eigen::Matrix3d* J_p) const {
  const Eigen::Matrix3d R = R_.matrix();
  if (J_this) {
    J_this->leftCols<3>() = R;
    J_this->rightCols<3>() = -R * SO3::hat(p);
  }
  if (J_p) *J_p = R;
  return R * p + t_;
}

SE3::Matrix6 SE3::adjoint() const {
  const Eigen::Matrix3d R = R_.matrix();
  Matrix6 A;
  A << R, SO3::hat(t_) * R, Eigen::Matrix3d::Zero(), R;
  return A;
}

SE3::Matrix6 SE3::right_jacobian(const Vector6& xi) {
  const Eigen::Vector3d rho = xi.head<3>(), phi = xi.tail<3>();
  const Eigen::Matrix3d Jr = SO3::right_jacobian(phi);
  Matrix6 J;
  J << Jr, barfoot_q(-rho, -phi), Eigen::Matrix3d::Zero(), Jr;
  return J;
}

SE3::Matrix6 SE3::right_jacobian_inverse(const Vector6& xi) {
  const Eigen::Vector3d rho = xi.head<3>(), phi = xi.tail<3>();
  const Eigen::Matrix3d Ji = SO3::right_jacobian_inverse(phi);
  Matrix6 J;
  J << Ji, -Ji * barfoot_q(-rho, -phi) * Ji, Eigen::Matrix3d::Zero(), Ji;
  return J;
}

Eigen::Isometry3d SE3::isometry() const {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = R_.matrix();
  x.translation() = t_;
  return x;
}

}  // namespace sextant
