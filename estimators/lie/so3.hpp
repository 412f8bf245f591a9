#pragma once
// SO(3), the group of 3-D rotations, stored as a unit quaternion.
//
// Conventions (shared by every group in estimators/lie): perturbations are on the right, X (+) w = X * Exp(w);
// Jacobians are of the right-perturbed output with respect to right-perturbed inputs.  Equation numbers refer to
// Sola, Deray, Atchuthan, "A micro Lie theory for state estimation in robotics", arXiv:1812.01537.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sextant {

class SO3 {
 public:
  SO3() = default;
  /// Normalizes `q`.  The sign of q is kept (q and -q are the same rotation).
  explicit SO3(const Eigen::Quaterniond& q) : q_(q.normalized()) {}
  explicit SO3(const Eigen::Matrix3d& R) : q_(Eigen::Quaterniond(R).normalized()) {}
  /// `q` as it is, not normalized again: for a quaternion that is already one of an SO3's (a restored state), so that
  /// it comes back bit for bit.
  static SO3 from_unit_quaternion(const Eigen::Quaterniond& q) {
    SO3 r;
    r.q_ = q;
    return r;
  }

  /// Exp: rotation vector (axis * angle, rad) -> rotation (eq. 132); J_right = Jr(w) (eq. 143).
  static SO3 exp(const Eigen::Vector3d& w, Eigen::Matrix3d* J_right = nullptr);
  /// Log: the rotation vector with angle in [0, pi] (eq. 133); J_right_inv = Jr^-1(log) (eq. 144).
  Eigen::Vector3d log(Eigen::Matrix3d* J_right_inv = nullptr) const;

  SO3 inverse() const { return SO3(q_.conjugate()); }
  SO3 operator*(const SO3& b) const { return SO3(q_ * b.q_); }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return q_ * p; }

  Eigen::Matrix3d matrix() const { return q_.toRotationMatrix(); }
  const Eigen::Quaterniond& quaternion() const { return q_; }
  /// Ad = R (eq. 140).
  Eigen::Matrix3d adjoint() const { return matrix(); }

  /// [v]x, the skew-symmetric matrix with [v]x p = v x p.
  static Eigen::Matrix3d hat(const Eigen::Vector3d& v);
  /// Right Jacobian Jr(w) = I - (1-cos t)/t^2 [w]x + (t - sin t)/t^3 [w]x^2 (eq. 143).
  static Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& w);
  /// Jr^-1(w) = I + 1/2 [w]x + (1/t^2 - (1+cos t)/(2 t sin t)) [w]x^2 (eq. 144).
  static Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& w);
  /// Left Jacobian Jl(w) = Jr(-w) (eq. 145); also the V matrix of SE(3)'s Exp.
  static Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& w) { return right_jacobian(-w); }

 private:
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
};

}  // namespace sextant
