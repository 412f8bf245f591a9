#pragma once
// SO(2), planar rotations, stored as an angle in (-pi, pi].  Exp/Log are the identity on the angle; every Jacobian
// of SO(2) is 1 (the group is commutative; Sola et al., arXiv:1812.01537, §A).
#include <Eigen/Core>

#include <cmath>

namespace sextant {

/// Wraps an angle to (-pi, pi].
inline double wrap_angle(double a) {
  if (a > -M_PI && a <= M_PI) return a;  // what remainder gives there, without its cost (most calls)
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

class SO2 {
 public:
  SO2() = default;
  explicit SO2(double angle) : angle_(wrap_angle(angle)) {}

  static SO2 exp(double theta) { return SO2(theta); }
  double log() const { return angle_; }
  double angle() const { return angle_; }
  SO2 inverse() const { return SO2(-angle_); }
  SO2 operator*(const SO2& b) const { return SO2(angle_ + b.angle_); }
  Eigen::Vector2d operator*(const Eigen::Vector2d& p) const { return matrix() * p; }
  Eigen::Matrix2d matrix() const {
    const double c = std::cos(angle_), s = std::sin(angle_);
    Eigen::Matrix2d R;
    R << c, -s, s, c;
    return R;
  }

 private:
  double angle_ = 0;
};

}  // namespace sextant
