#pragma once
// SE(3), rigid motions in 3-D: a rotation R and a translation t acting as p -> R p + t.
// Tangent vectors are xi = [rho; phi] (translation first, then rotation), perturbations on the right:
// X (+) xi = X * Exp(xi).  Equation numbers: Sola et al., arXiv:1812.01537 (§ and appendix D).
#include "estimators/lie/so3.hpp"

namespace sextant {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

class SE3 {
 public:
  using Vector6 = Vector6d;
  using Matrix6 = Matrix6d;

  SE3() = default;
  SE3(const SO3& R, const Eigen::Vector3d& t) : R_(R), t_(t) {}
  SE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) : R_(q), t_(t) {}

  /// Exp (eq. 172): R = Exp(phi), t = Jl(phi) rho.  J_right = Jr(xi) (eq. 179).
  static SE3 exp(const Vector6& xi, Matrix6* J_right = nullptr);
  /// Log (eq. 173): phi = Log(R), rho = Jl(phi)^-1 t.  J_right_inv = Jr(xi)^-1.
  Vector6 log(Matrix6* J_right_inv = nullptr) const;

  SE3 inverse(Matrix6* J = nullptr) const;
  SE3 operator*(const SE3& b) const { return SE3(R_ * b.R_, R_ * b.t_ + t_); }
  /// this * b, with J_this = Ad(b^-1) and J_b = I (eq. 175-176).
  SE3 compose(const SE3& b, Matrix6* J_this = nullptr, Matrix6* J_b = nullptr) const;
  /// this^-1 * b, with J_this = -Ad((this^-1 b)^-1) and J_b = I.
  SE3 between(const SE3& b, Matrix6* J_this = nullptr, Matrix6* J_b = nullptr) const;

  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return R_ * p + t_; }
  /// R p + t, with J_this = [R, -R [p]x] and J_p = R (eq. 178).
  Eigen::Vector3d act(const Eigen::Vector3d& p, Eigen::Matrix<double, 3, 6>* J_this = nullptr,
                      Eigen::Matrix3d* J_p = nullptr) const;

  /// Ad = [R, [t]x R; 0, R] (eq. 174).
  Matrix6 adjoint() const;
  /// Jr(xi) = [Jr(phi), Q(-rho, -phi); 0, Jr(phi)], Q from Barfoot & Furgale (2014), eq. 102.
  static Matrix6 right_jacobian(const Vector6& xi);
  static Matrix6 right_jacobian_inverse(const Vector6& xi);

  const SO3& rotation() const { return R_; }
  const Eigen::Vector3d& translation() const { return t_; }
  Eigen::Isometry3d isometry() const;

 private:
  SO3 R_;
  Eigen::Vector3d t_ = Eigen::Vector3d::Zero();
};

}  // namespace sextant
