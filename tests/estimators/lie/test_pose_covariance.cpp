// Covariances of poses under the right perturbation (estimators/lie/pose_covariance.hpp) against independent
// computations: the composition's Jacobian by central differences on SE(3), the differential increment and its
// regularization by hand on diagonal matrices.
#include "estimators/lie/pose_covariance.hpp"

#include "estimators/lie/pose_test_values.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

#include <numbers>
#include <optional>

using namespace sextant;
using sextant::test::max_abs;
using sextant::test::pose;

namespace {

Matrix6d spd(int seed) { return test::spd(seed, 0.1); }

// d Log((X Delta)^-1 X Exp(h e_k) Delta) / dh at h = 0, by central differences: how a right perturbation of X
// appears on X Delta.
Matrix6d numeric_transport(const SE3& X, const SE3& delta) {
  const double h = 1e-6;
  const SE3 Y = X * delta;
  Matrix6d J;
  for (int k = 0; k < 6; ++k) {
    Vector6d e = Vector6d::Zero();
    e[k] = h;
    const Vector6d plus = Y.between(X * SE3::exp(e) * delta).log();
    const Vector6d minus = Y.between(X * SE3::exp(-e) * delta).log();
    J.col(k) = (plus - minus) / (2 * h);
  }
  return J;
}

}  // namespace

TEST_CASE("compose_covariance: J P J' + Q with J the numeric transport of a right perturbation through Delta") {
  const SE3 X = pose(1.0, -2.0, 0.5, 0.3, -0.2, 1.1);
  const SE3 delta = pose(0.8, 0.3, -0.1, 0.2, 0.4, -0.7);
  const Matrix6d P = spd(1), Q = spd(2);
  const Matrix6d J = numeric_transport(X, delta);
  const Matrix6d expected = J * P * J.transpose() + Q;
  const Matrix6d got = compose_covariance(P, delta, Q);
  CHECK(max_abs(got - expected) < 1e-8 * max_abs(expected));
  CHECK(max_abs(got - got.transpose()) == 0.0);  // symmetrized exactly
  // The identity motion transports nothing: P + Q.
  CHECK(max_abs(compose_covariance(P, SE3(), Q) - (P + Q)) < 1e-15);
  // A pure translation leaves the rotation block alone and feeds rotation uncertainty into the translation: a yaw
  // error e of X moves the point 1 m ahead of it by e to the left (+y), so a yaw variance s becomes a variance s in
  // y, fully correlated with the yaw.
  Matrix6d yaw = Matrix6d::Zero();
  yaw(5, 5) = 0.04;
  const Matrix6d moved = compose_covariance(yaw, pose(1, 0, 0, 0, 0, 0), Matrix6d::Zero());
  CHECK(moved(5, 5) == doctest::Approx(0.04));
  CHECK(moved(1, 1) == doctest::Approx(0.04));
  CHECK(moved(1, 5) == doctest::Approx(0.04));
  CHECK(moved(0, 0) == doctest::Approx(0.0));
}

TEST_CASE("stated_increment_covariance: the stated one, else the growth of the pose covariance since the previous") {
  const SE3 delta = pose(0.5, 0.1, 0.0, 0.0, 0.0, 0.3);
  const Matrix6d prev = spd(3), stated = spd(4);
  const Matrix6d now = compose_covariance(prev, delta, stated);  // a sender that composed `stated` onto `prev`
  // Stated: returned as is, whatever the pose covariances say.
  CHECK(stated_increment_covariance(now, stated, delta, prev) == stated);
  CHECK(stated_increment_covariance(Matrix6d::Zero(), stated, delta, Matrix6d::Identity()) == stated);
  // Differential: the growth recovers what the sender composed.
  const Matrix6d growth = stated_increment_covariance(now, std::nullopt, delta, prev);
  CHECK(max_abs(growth - stated) < 1e-12);
  // By hand: no motion, diagonal covariances: the difference of the diagonals, negative entries kept (unregularized).
  Matrix6d before = Matrix6d::Identity(), after = 2 * Matrix6d::Identity();
  after(2, 2) = 0.5;
  Matrix6d hand = Matrix6d::Identity();
  hand(2, 2) = -0.5;
  CHECK(max_abs(stated_increment_covariance(after, std::nullopt, SE3(), before) - hand) < 1e-15);
}

TEST_CASE("regularized_increment_covariance: eigenvalues on the used axes floored at min_variance, stated or growth") {
  const double mv = 1e-6;
  // Differential and indefinite, no motion: the growth diag(1, -0.5, 0, 0, 0, 2); its eigenvalues on the used axes
  // floored at min_variance: x, y, yaw only when planar (z, roll, pitch as they are), all six when not.
  Matrix6d before = Matrix6d::Identity();
  Matrix6d after = Matrix6d::Identity();
  after(0, 0) = 2, after(1, 1) = 0.5, after(5, 5) = 3;
  for (int i : {2, 3, 4}) after(i, i) = 1;  // no growth on z, roll, pitch
  const Matrix6d planar = regularized_increment_covariance(after, std::nullopt, true, SE3(), before, mv);
  Eigen::Matrix<double, 6, 1> d;
  d << 1, mv, 0, 0, 0, 2;
  CHECK(max_abs(planar - Matrix6d(d.asDiagonal())) < 1e-14);
  const Matrix6d spatial = regularized_increment_covariance(after, std::nullopt, false, SE3(), before, mv);
  d << 1, mv, mv, mv, mv, 2;
  CHECK(max_abs(spatial - Matrix6d(d.asDiagonal())) < 1e-14);
  CHECK(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(planar_block(planar)).eigenvalues().minCoeff() ==
        doctest::Approx(mv));

  // Stated and well above the floor: kept as stated (to rounding); the entries off the used axes untouched.
  Matrix6d stated = Matrix6d::Zero();
  stated(0, 0) = 0.01, stated(0, 1) = stated(1, 0) = 0.002, stated(1, 1) = 0.02, stated(5, 5) = 0.003;
  stated(2, 2) = 0.5;  // z: not a planar body's axis
  CHECK(max_abs(regularized_increment_covariance(Matrix6d::Identity(), stated, true, pose(1, 2, 0, 0, 0, 1),
                                                 Matrix6d::Zero(), mv) -
                stated) < 1e-15);
  // Stated with a direction below the floor (yaw 1e-9): that direction raised to min_variance, the others kept.
  Matrix6d thin = stated;
  thin(5, 5) = 1e-9;
  Matrix6d expected = thin;
  expected(5, 5) = mv;
  CHECK(max_abs(regularized_increment_covariance(Matrix6d::Zero(), thin, true, SE3(), Matrix6d::Zero(), mv) -
                expected) < 1e-15);
}

TEST_CASE("nearest_psd: eigenvalues floored at zero, eigenvectors kept (Higham 1988)") {
  // [[1, 2], [2, 1]] on (x, y): eigenvalues 3 on (1, 1)/sqrt2 and -1 on (1, -1)/sqrt2: the projection is
  // 3 a a' = [[1.5, 1.5], [1.5, 1.5]]; the rest of the diagonal untouched.
  Matrix6d m = Matrix6d::Identity();
  m(0, 0) = 1, m(0, 1) = m(1, 0) = 2, m(1, 1) = 1;
  Matrix6d expected = Matrix6d::Identity();
  expected.topLeftCorner<2, 2>().setConstant(1.5);
  CHECK(max_abs(nearest_psd(m) - expected) < 1e-14);
  const Matrix6d already = spd(5);
  CHECK(max_abs(nearest_psd(already) - already) < 1e-14);
}

TEST_CASE("right_perturbation_from_world_position: an error-state filter's [dp world; theta] as [rho; theta]") {
  // The filter's error (p_hat + dp, R_hat Exp(theta)) seen as a right perturbation xi = Log(T_hat^-1 T): its
  // Jacobian at zero by central differences, against the closed form blockdiag(R_hat', I).
  const SE3 T_hat = pose(1.0, -2.0, 0.5, 0.3, -0.2, 1.1);
  const double h = 1e-6;
  Matrix6d J;
  for (int k = 0; k < 6; ++k) {
    Vector6d e = Vector6d::Zero();
    e[k] = h;
    const auto perturbed = [&](const Vector6d& err) {
      return SE3(T_hat.rotation() * SO3::exp(err.tail<3>()), T_hat.translation() + err.head<3>());
    };
    J.col(k) = (T_hat.between(perturbed(e)).log() - T_hat.between(perturbed(-e)).log()) / (2 * h);
  }
  const Matrix6d P = spd(3);
  const Matrix6d expected = J * P * J.transpose();
  const Matrix6d got = right_perturbation_from_world_position(T_hat.rotation().matrix(), P);
  CHECK(max_abs(got - expected) < 1e-8 * max_abs(expected));
  // A body facing north (yaw 90 degrees) that is uncertain along east is uncertain along its own y axis (west).
  Matrix6d east = Matrix6d::Zero();
  east(0, 0) = 4.0;
  const Matrix6d facing_north =
      right_perturbation_from_world_position(pose(0, 0, 0, 0, 0, std::numbers::pi / 2).rotation().matrix(), east);
  CHECK(facing_north(1, 1) == doctest::Approx(4.0));
  CHECK(facing_north(0, 0) == doctest::Approx(0.0).epsilon(1e-12));
}
