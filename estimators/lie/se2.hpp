#pragma once
// SE(2), rigid motions in the plane: heading theta and translation t, acting as p -> R(theta) p + t.
// Tangent vectors are [x, y, theta] (translation first), perturbations on the right: X (+) tau = X * Exp(tau).
// Equation numbers: Sola et al., arXiv:1812.01537, appendix C.
#include "estimators/lie/se3.hpp"
#include "estimators/lie/so2.hpp"

namespace sextant {

class SE2 {
 public:
  SE2() = default;
  SE2(double x, double y, double theta) : R_(theta), t_(x, y) {}
  SE2(const SO2& R, const Eigen::Vector2d& t) : R_(R), t_(t) {}

  /// Exp (eq. 156): theta, t = V(theta) rho.  J_right = Jr(tau) (eq. 163).
  static SE2 exp(const Eigen::Vector3d& tau, Eigen::Matrix3d* J_right = nullptr);
  /// Log (eq. 157), theta in (-pi, pi].  J_right_inv = Jr(tau)^-1.
  Eigen::Vector3d log(Eigen::Matrix3d* J_right_inv = nullptr) const;

  SE2 inverse(Eigen::Matrix3d* J = nullptr) const;
  SE2 operator*(const SE2& b) const { return SE2(R_ * b.R_, R_ * b.t_ + t_); }
  /// this * b, with J_this = Ad(b^-1), J_b = I.
  SE2 compose(const SE2& b, Eigen::Matrix3d* J_this = nullptr, Eigen::Matrix3d* J_b = nullptr) const;
  /// this^-1 * b, with J_this = -Ad((this^-1 b)^-1), J_b = I.
  SE2 between(const SE2& b, Eigen::Matrix3d* J_this = nullptr, Eigen::Matrix3d* J_b = nullptr) const;
  /// R p + t, with J_this = [R, R [1]x p] and J_p = R (eq. 165).
  Eigen::Vector2d act(const Eigen::Vector2d& p, Eigen::Matrix<double, 2, 3>* J_this = nullptr,
                      Eigen::Matrix2d* J_p = nullptr) const;

  /// Ad = [R, [y; -x]; 0, 1] (eq. 161).
  Eigen::Matrix3d adjoint() const;
  static Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& tau);

  double angle() const { return R_.angle(); }
  const SO2& rotation() const { return R_; }
  const Eigen::Vector2d& translation() const { return t_; }
  /// As an SE(3) element with z = 0 and rotation about +z.
  SE3 to_se3() const;
  /// The planar part of an SE(3) element: x, y and the yaw of its rotation.
  static SE2 from_se3(const SE3& x);

 private:
  SO2 R_;
  Eigen::Vector2d t_ = Eigen::Vector2d::Zero();
};

}  // namespace sextant
