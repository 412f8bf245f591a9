// The smoother's odometry and loop factors (estimators/slam/pose_factors.hpp) against hand-computed informations and
// the chi2 a small tangent error must cost.
#include "estimators/slam/pose_factors.hpp"

#include "estimators/lie/planar_axes.hpp"
#include "estimators/lie/pose_test_values.hpp"
#include "estimators/lie/se2.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <vector>

using namespace sextant;
using namespace sextant::slam;
using sextant::test::max_abs;
using sextant::test::pose;
using sextant::test::spd;

namespace {

// The chi2 e' Omega e of a two-pose factor with its poses at a and b.
double chi2(const graph::Factor& f, const SE3& a, const SE3& b) {
  std::vector<graph::Variable> vars(2);
  for (auto& v : vars) v.kind = graph::VariableKind::kPose3;
  vars[0].pose3 = a, vars[1].pose3 = b;
  Eigen::VectorXd e(f.residual_dim());
  f.error(vars, e);
  return e.dot(f.information() * e);
}

}  // namespace

TEST_CASE("residual_information: T Omega T with T = diag(I, 2 I), a small tangent error then costs xi' Omega xi") {
  const Matrix6d omega = spd(1);
  Matrix6d T = Matrix6d::Identity();
  T.bottomRightCorner<3, 3>() *= 2;
  const Matrix6d r = residual_information(omega);
  CHECK(max_abs(r - T * omega * T) == 0.0);  // powers of two: exact
  CHECK(r.topLeftCorner<3, 3>() == omega.topLeftCorner<3, 3>());
  CHECK(r.bottomRightCorner<3, 3>() == 4 * omega.bottomRightCorner<3, 3>());
  CHECK(r.topRightCorner<3, 3>() == 2 * omega.topRightCorner<3, 3>());

  // The loop z between a and b = a z Exp(xi): the factor's chi2 is xi' Omega xi to first order in xi.
  const SE3 a = pose(1, 2, 0.5, 0.1, -0.3, 0.7), z = pose(3, -1, 0.2, 0.4, 0.1, -0.5);
  Vector6d xi;
  xi << 2e-4, -1e-4, 3e-4, 1e-4, -2e-4, 1.5e-4;
  const SE3 b = a * z * SE3::exp(xi);
  const auto loop = loop_factor(false, 0, 1, z, omega);
  const double tangent_chi2 = xi.dot(omega * xi);
  CHECK(chi2(*loop, a, b) == doctest::Approx(tangent_chi2).epsilon(1e-3));
  // A rotation-only error with Omega passed unchanged would cost a quarter of it (the bug T Omega T fixes).
  Vector6d phi = Vector6d::Zero();
  phi.tail<3>() << 1e-4, -2e-4, 1.5e-4;
  const graph::RelativePoseFactor unscaled(0, 1, z, omega);
  CHECK(chi2(unscaled, a, a * z * SE3::exp(phi)) == doctest::Approx(0.25 * phi.dot(omega * phi)).epsilon(1e-3));
  CHECK(chi2(*loop_factor(false, 0, 1, z, omega), a, a * z * SE3::exp(phi)) ==
        doctest::Approx(phi.dot(omega * phi)).epsilon(1e-3));
}

TEST_CASE("odometry_factor: the inverse of the covariance (planar: of its x, y, yaw block), or none when it has none") {
  // Planar, by hand: [[0.04, 0.01], [0.01, 0.09]] on (x, y) has inverse [[0.09, -0.01], [-0.01, 0.04]] / 0.0035;
  // yaw 0.0025 gives 400.  z, roll and pitch are zero: a planar body's covariance need not hold them.
  Matrix6d c = Matrix6d::Zero();
  c(0, 0) = 0.04, c(0, 1) = c(1, 0) = 0.01, c(1, 1) = 0.09, c(5, 5) = 0.0025;
  const SE3 edge = SE2(1.0, 0.5, 0.3).to_se3();
  const auto f = odometry_factor(true, 4, 7, edge, c);
  REQUIRE(f != nullptr);
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected(0, 0) = 0.09 / 0.0035, expected(0, 1) = expected(1, 0) = -0.01 / 0.0035, expected(1, 1) = 0.04 / 0.0035;
  expected(2, 2) = 400;
  CHECK(max_abs(f->information() - expected) < 1e-9);
  CHECK(f->variables() == std::vector<int>{4, 7});
  const auto& rp = dynamic_cast<const graph::RelativePoseFactor&>(*f);
  CHECK(rp.planar());
  CHECK((rp.measurement2().log() - SE2(1.0, 0.5, 0.3).log()).norm() < 1e-12);

  // 3-D: the residual information of the covariance's inverse.
  const Matrix6d c3 = 0.01 * spd(2);
  const SE3 edge3 = pose(0.5, -0.2, 0.1, 0.05, 0.02, -0.1);
  const auto f3 = odometry_factor(false, 0, 1, edge3, c3);
  REQUIRE(f3 != nullptr);
  CHECK(max_abs(f3->information() - residual_information(c3.inverse())) < 1e-9 * max_abs(c3.inverse()));
  // Exactly symmetric (symmetrized, not averaged in place: that aliasing left rounding-sized asymmetries).
  CHECK(f3->information() == f3->information().transpose());
  CHECK(f->information() == f->information().transpose());
  CHECK(dynamic_cast<const graph::RelativePoseFactor&>(*f3).measurement3().log() == edge3.log());

  // None: an indefinite block, a NaN, and a 3-D body with a planar (singular) covariance.
  Matrix6d indefinite = c;
  indefinite(0, 1) = indefinite(1, 0) = 0.1;  // 0.04 * 0.09 < 0.1^2
  CHECK(odometry_factor(true, 0, 1, edge, indefinite) == nullptr);
  Matrix6d nan = c;
  nan(5, 5) = std::numeric_limits<double>::quiet_NaN();
  CHECK(odometry_factor(true, 0, 1, edge, nan) == nullptr);
  CHECK(odometry_factor(false, 0, 1, edge, c) == nullptr);
}

TEST_CASE("loop_factor: the information's x, y, yaw block when planar, its residual information in 3-D") {
  const Matrix6d omega = spd(3);
  const SE3 z = SE2(-2.0, 1.0, -0.4).to_se3();
  const auto planar = loop_factor(true, 2, 3, z, omega);
  Eigen::Matrix3d block;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) block(r, c) = omega(kPlanarAxes[r], kPlanarAxes[c]);
  CHECK(planar->information() == Eigen::MatrixXd(block));
  CHECK(dynamic_cast<const graph::RelativePoseFactor&>(*planar).planar());
  const auto spatial = loop_factor(false, 2, 3, z, omega);
  CHECK(spatial->information() == Eigen::MatrixXd(residual_information(omega)));
  CHECK_FALSE(dynamic_cast<const graph::RelativePoseFactor&>(*spatial).planar());
}
