// The covariance of the odometry edge across a jump (estimators/slam/jump_covariance.hpp), by hand: each translation
// axis gets |rho|^2, each rotation axis |phi|^2, of mu = Log(edge); planar bodies only x, y and yaw.
#include "estimators/slam/jump_covariance.hpp"

#include "estimators/lie/pose_test_values.hpp"

#include <doctest/doctest.h>

using namespace sextant;
using namespace sextant::slam;
using sextant::test::max_abs;

namespace {

Matrix6d diagonal(double a, double b, double c, double d, double e, double f) {
  return Matrix6d(test::tangent(a, b, c, d, e, f).asDiagonal());
}

}  // namespace

TEST_CASE("jump covariance, planar: |rho|^2 on x and y, yaw^2 on yaw, nothing on z, roll, pitch") {
  // A pure translation (3, 4): rho = (3, 4), |rho|^2 = 25.
  CHECK(max_abs(jump_covariance(SE2(3, 4, 0).to_se3(), true) - diagonal(25, 25, 0, 0, 0, 0)) < 1e-12);
  // mu = (1, -2, 0.5) through Exp: |rho|^2 = 5, yaw^2 = 0.25.
  const SE3 edge = SE2::exp(Eigen::Vector3d(1, -2, 0.5)).to_se3();
  CHECK(max_abs(jump_covariance(edge, true) - diagonal(5, 5, 0, 0, 0, 0.25)) < 1e-12);
  // The height and tilt of an edge are ignored for a planar body.
  CHECK(max_abs(jump_covariance(test::pose(3, 4, 7, 0, 0, 0), true) - diagonal(25, 25, 0, 0, 0, 0)) < 1e-12);
}

TEST_CASE("jump covariance, 3-D: |rho|^2 on each translation axis, |phi|^2 on each rotation axis") {
  // A screw along z: rotation 0.3 about z and translation 2 along it: Log gives rho = (0, 0, 2) (V leaves the axis
  // alone), phi = (0, 0, 0.3).
  const SE3 screw(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(0, 0, 2));
  CHECK(max_abs(jump_covariance(screw, false) - diagonal(4, 4, 4, 0.09, 0.09, 0.09)) < 1e-12);
  // A pure translation (1, 2, 2): |rho|^2 = 9, no rotation.
  const SE3 step(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 2));
  CHECK(max_abs(jump_covariance(step, false) - diagonal(9, 9, 9, 0, 0, 0)) < 1e-12);
  // The identity: no jump, no covariance.
  CHECK(max_abs(jump_covariance(SE3(), false)) == 0.0);
  CHECK(max_abs(jump_covariance(SE3(), true)) == 0.0);
}
