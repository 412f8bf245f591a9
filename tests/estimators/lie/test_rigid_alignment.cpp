#include "estimators/lie/rigid_alignment.hpp"

#include <doctest/doctest.h>

#include <random>

using namespace sextant;

TEST_CASE("align_points recovers a known rigid motion, planar and 3-D, and fits noisy points in least squares") {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  Eigen::Matrix3Xd a(3, 20);
  for (int k = 0; k < 20; ++k) a.col(k) = Eigen::Vector3d(5 * n(rng), 5 * n(rng), 2 * n(rng));
  SUBCASE("3-D") {
    Vector6d xi;
    xi << 1, -2, 0.5, 0.3, -0.4, 1.2;
    const SE3 t = SE3::exp(xi);
    Eigen::Matrix3Xd b(3, 20);
    for (int k = 0; k < 20; ++k) b.col(k) = t * Eigen::Vector3d(a.col(k));
    const RigidAlignment r = align_points(a, b);
    CHECK((r.rotation - t.rotation().matrix()).norm() < 1e-9);
    CHECK((r.translation - t.translation()).norm() < 1e-9);
  }
  SUBCASE("planar: the rotation is about z alone, whatever z the points have") {
    const Eigen::Matrix3d rz = Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    Eigen::Matrix3Xd b = (rz * a).colwise() + Eigen::Vector3d(3, -1, 0);
    b.row(2) = Eigen::RowVectorXd::Random(20);  // heights that disagree do not tilt a planar fit
    const RigidAlignment r = align_points(a, b, false, true);
    CHECK((r.rotation - rz).norm() < 1e-9);
    CHECK((r.translation - Eigen::Vector3d(3, -1, 0)).norm() < 1e-9);
  }
  SUBCASE("noise: the residual of the fit is smaller than that of the true motion") {
    Eigen::Matrix3Xd b = a;
    for (int k = 0; k < 20; ++k) b.col(k) += 0.1 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const RigidAlignment r = align_points(a, b);
    const double fitted = ((r.rotation * a).colwise() + r.translation - b).squaredNorm();
    CHECK(fitted <= (a - b).squaredNorm());
    CHECK(r.rotation.determinant() == doctest::Approx(1.0));
  }
  CHECK_THROWS_AS(align_points(a, Eigen::Matrix3Xd(3, 3)), std::invalid_argument);
}
