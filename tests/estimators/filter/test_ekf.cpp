// The Kalman update against the textbook linear Kalman filter, the planar EKF's Jacobians against central
// differences, gating, NaN rejection and a covariance that stays symmetric positive definite.
#include "estimators/filter/planar_ekf.hpp"
#include "estimators/filter/state_augmentation.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

#include <random>

using namespace sextant;
using namespace sextant::filter;

TEST_CASE("Joseph-form update equals an independent linear Kalman filter on a linear system") {
  // x_k = A x + B u + w, z = C x + v (the Kalman filter: Thrun, Burgard & Fox, Probabilistic Robotics, Table 3.1),
  // 4 states, 2 measurements, 50 steps.
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  Eigen::Matrix4d A;
  A << 1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.1, 0, 0, 0, 1;
  Eigen::Matrix<double, 4, 2> B;
  B << 0.005, 0, 0.1, 0, 0, 0.005, 0, 0.1;
  Eigen::Matrix<double, 2, 4> C;
  C << 1, 0, 0, 0, 0, 0, 1, 0;
  const Eigen::Matrix4d Rw = 0.01 * Eigen::Matrix4d::Identity();
  const Eigen::Matrix2d Qv = 0.25 * Eigen::Matrix2d::Identity();
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4), xt = x, truth = Eigen::Vector4d(0, 1, 0, -1);
  Eigen::MatrixXd P = Eigen::MatrixXd::Identity(4, 4), Pt = P;
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d u(n(rng), n(rng));
    truth = A * truth + B * u;
    const Eigen::Vector2d z = C * truth + Eigen::Vector2d(0.5 * n(rng), 0.5 * n(rng));
    // Textbook (the survey's equations): predict, K = P C' (C P C' + Q)^-1, x += K (z - C x), P = (I - K C) P.
    xt = A * xt + B * u;
    Pt = A * Pt * A.transpose() + Rw;
    const Eigen::MatrixXd K = Pt * C.transpose() * (C * Pt * C.transpose() + Qv).inverse();
    xt = xt + K * (z - C * xt);
    Pt = (Eigen::Matrix4d::Identity() - K * C) * Pt;
    // sextant's update.
    x = A * x + B * u;
    P = A * P * A.transpose() + Rw;
    const Eigen::VectorXd r = z - C * x;
    const auto res = kalman_update(x, P, r, C, Qv, 0);
    REQUIRE(res.accepted);
    CHECK((x - xt).norm() < 1e-10);
    CHECK((P - Pt).norm() < 1e-10);
  }
}

TEST_CASE("planar EKF: motion and observation Jacobians against central differences") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d x(u(rng), u(rng), u(rng));
    const SE2 d(0.3 * u(rng), 0.1 * u(rng), 0.2 * u(rng));
    Eigen::Matrix3d F, G;
    PlanarEkf::motion(x, d, &F, &G);
    const double h = 1e-6;
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[c] = h;
      Eigen::Vector3d diff =
          PlanarEkf::motion(x + e, d, nullptr, nullptr) - PlanarEkf::motion(x - e, d, nullptr, nullptr);
      diff[2] = wrap_angle(diff[2]);
      CHECK((diff / (2 * h) - F.col(c)).norm() < 1e-6);
      // Noise enters on the right of the increment: Delta (+) w.
      Eigen::Vector3d dw = (PlanarEkf::motion(x, d * SE2::exp(e), nullptr, nullptr) -
                            PlanarEkf::motion(x, d * SE2::exp(-e), nullptr, nullptr));
      dw[2] = wrap_angle(dw[2]);
      CHECK((dw / (2 * h) - G.col(c)).norm() < 1e-6);
    }
    const Eigen::Vector2d l(x.x() + 3 + u(rng), x.y() + u(rng));
    Eigen::Matrix<double, 2, 3> Hx;
    Eigen::Matrix2d Hl;
    PlanarEkf::observation(x, l, &Hx, &Hl);
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[c] = h;
      Eigen::Vector2d diff =
          PlanarEkf::observation(x + e, l, nullptr, nullptr) - PlanarEkf::observation(x - e, l, nullptr, nullptr);
      diff[1] = wrap_angle(diff[1]);
      CHECK((diff / (2 * h) - Hx.col(c)).norm() < 1e-6);
    }
    for (int c = 0; c < 2; ++c) {
      Eigen::Vector2d e = Eigen::Vector2d::Zero();
      e[c] = h;
      Eigen::Vector2d diff =
          PlanarEkf::observation(x, l + e, nullptr, nullptr) - PlanarEkf::observation(x, l - e, nullptr, nullptr);
      diff[1] = wrap_angle(diff[1]);
      CHECK((diff / (2 * h) - Hl.col(c)).norm() < 1e-6);
    }
  }
}

TEST_CASE("planar EKF-SLAM: localization converges, outliers are gated, NaN refused, P stays SPD") {
  // A robot circles among 6 landmarks; the map is unknown (SLAM) except landmark 0.
  std::mt19937 rng(9);
  std::normal_distribution<double> n(0, 1);
  std::vector<Eigen::Vector2d> lm = {{4, 0}, {0, 4}, {-4, 0}, {0, -4}, {3, 3}, {-3, -3}};
  PlanarEkf ekf;
  ekf.set_known_landmark(0, lm[0]);
  SE2 truth(2, 0, M_PI / 2);
  ekf.initialize(truth, Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal());
  const SE2 step(0.1, 0, 0.05);
  const Eigen::Matrix3d Q = Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal();
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.0004).asDiagonal();
  int gated = 0, accepted = 0;
  for (int k = 0; k < 600; ++k) {
    truth = truth * step;
    const SE2 noisy = step * SE2::exp(Eigen::Vector3d(0.01 * n(rng), 0.01 * n(rng), 0.003 * n(rng)));
    ekf.predict(noisy, Q);
    for (size_t i = 0; i < lm.size(); ++i) {
      const Eigen::Vector3d xt(truth.translation().x(), truth.translation().y(), truth.angle());
      const Eigen::Vector2d z =
          PlanarEkf::observation(xt, lm[i], nullptr, nullptr) + Eigen::Vector2d(0.1 * n(rng), 0.02 * n(rng));
      const auto r = ekf.observe(static_cast<int64_t>(i), z[0], z[1], R);
      accepted += r.accepted;
    }
    if (k % 50 == 0) {
      const auto r = ekf.observe(1, 25.0, 1.0, R);  // a wild outlier of a known landmark
      gated += r.reason == UpdateReason::kGate;
    }
  }
  CHECK(gated == 12);
  CHECK(accepted > 3000);
  CHECK((ekf.pose().translation() - truth.translation()).norm() < 0.1);
  CHECK(std::abs(wrap_angle(ekf.pose().angle() - truth.angle())) < 0.03);
  for (const auto& [id, p] : ekf.landmarks()) CHECK((p - lm[static_cast<size_t>(id)]).norm() < 0.2);
  CHECK(ekf.landmark_count() == 5);
  const auto& P = ekf.covariance();
  CHECK((P - P.transpose()).norm() == 0.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(P);
  CHECK(eig.eigenvalues().minCoeff() > 0);
  const auto bad = ekf.observe(2, std::nan(""), 0.1, R);
  CHECK_FALSE(bad.accepted);
  CHECK(bad.reason == UpdateReason::kNonFinite);
}

TEST_CASE("a spurious unidentified sighting stays tentative and is forgotten, a repeated one is confirmed") {
  PlanarEkfOptions o;
  o.tentative_lifetime = 5;
  PlanarEkf ekf(o);
  ekf.initialize(SE2(0, 0, 0), Eigen::Matrix3d::Identity() * 1e-6);
  const Eigen::Matrix2d R = Eigen::Vector2d(0.01, 0.0001).asDiagonal();
  auto a = ekf.observe_unidentified({{5.0, 0.3, R}});  // once only
  CHECK(a.tentative == 1);
  for (int k = 0; k < 10; ++k) ekf.observe_unidentified({{3.0, -1.0, R}});  // a real one, seen again and again
  CHECK(ekf.landmark_count() == 1);
  const auto lm = ekf.landmarks();
  REQUIRE(lm.size() == 1);
  const Eigen::Vector2d expected(3 * std::cos(-1.0), 3 * std::sin(-1.0));
  CHECK((lm.begin()->second - expected).norm() < 0.05);
  // The spurious one never joined the state, and a later sighting near it starts over as tentative.
  a = ekf.observe_unidentified({{5.0, 0.3, R}});
  CHECK(a.tentative == 1);
  CHECK(a.confirmed == 0);
}

TEST_CASE("state augmentation equals the dense Jacobian transform J blockdiag(P, R) J' and refuses bad sizes") {
  // l = g(x_r, z) appended to a 7-state [robot(3); landmark(2); landmark(2)]: J = [I 0; Jx 0 Jz] (independent
  // computation of the same covariance).
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXd A(7, 7), Jx(2, 3), Jz(2, 2), B(2, 2);
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 7; ++c) A(r, c) = n(rng);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c) Jx(r, c) = n(rng);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) Jz(r, c) = n(rng), B(r, c) = n(rng);
  const Eigen::MatrixXd P = A * A.transpose() + Eigen::MatrixXd::Identity(7, 7);
  const Eigen::MatrixXd R = B * B.transpose() + 0.1 * Eigen::MatrixXd::Identity(2, 2);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(9, 9);
  J.topLeftCorner(7, 7).setIdentity();
  J.block(7, 0, 2, 3) = Jx;
  J.block(7, 7, 2, 2) = Jz;
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(9, 9);
  D.topLeftCorner(7, 7) = P;
  D.bottomRightCorner(2, 2) = R;
  const Eigen::MatrixXd expected = J * D * J.transpose();
  const Eigen::MatrixXd got = augmented_covariance(P, Jx, Jz, R);
  REQUIRE(got.rows() == 9);
  CHECK((got - expected).cwiseAbs().maxCoeff() < 1e-12 * expected.cwiseAbs().maxCoeff());
  CHECK((got - got.transpose()).cwiseAbs().maxCoeff() == 0.0);
  CHECK(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(got).eigenvalues().minCoeff() > 0);
  CHECK_THROWS_WITH(augmented_covariance(P, Eigen::MatrixXd::Zero(2, 8), Jz, R),
                    doctest::Contains("augmented_covariance"));
  CHECK_THROWS_WITH(augmented_covariance(P, Jx, Jz, Eigen::MatrixXd::Zero(3, 3)),
                    doctest::Contains("augmented_covariance"));
}
