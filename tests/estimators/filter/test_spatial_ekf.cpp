// The 3-D EKF: Jacobians of the motion, observation and landmark initialization against central differences on
// the manifold; EKF-SLAM on a 3-D run converges, gates an outlier, refuses NaN, keeps P symmetric positive definite.
#include "estimators/filter/spatial_ekf.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>

#include <random>

using namespace sextant;
using namespace sextant::filter;

namespace {
SE3 random_pose(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1, 1);
  SE3::Vector6 xi;
  for (int i = 0; i < 6; ++i) xi[i] = scale * u(rng);
  return SE3::exp(xi);
}
}  // namespace

TEST_CASE("3-D EKF: motion, observation and initialization Jacobians against central differences") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = 1e-6;
  for (int trial = 0; trial < 20; ++trial) {
    const SE3 X = random_pose(rng, 2), D = random_pose(rng, 0.3);
    // Motion: Log((X D)^-1 (X Exp(e) D)) = Ad(D^-1) e.
    const SE3::Matrix6 F = D.inverse().adjoint();
    for (int c = 0; c < 6; ++c) {
      SE3::Vector6 e = SE3::Vector6::Zero();
      e[c] = h;
      const SE3::Vector6 d =
          ((X * D).inverse() * (X * SE3::exp(e) * D)).log() - ((X * D).inverse() * (X * SE3::exp(-e) * D)).log();
      CHECK((d / (2 * h) - F.col(c)).norm() < 1e-6);
    }
    const Eigen::Vector3d l =
        X.translation() + X.rotation().matrix() * Eigen::Vector3d(3 + u(rng), u(rng), 0.5 * u(rng));
    Eigen::Matrix<double, 3, 6> Hx;
    Eigen::Matrix3d Hl;
    const Eigen::Vector3d z = SpatialEkf::observation(X, l, &Hx, &Hl);
    for (int c = 0; c < 6; ++c) {
      SE3::Vector6 e = SE3::Vector6::Zero();
      e[c] = h;
      Eigen::Vector3d d = SpatialEkf::observation(X * SE3::exp(e), l, nullptr, nullptr) -
                          SpatialEkf::observation(X * SE3::exp(-e), l, nullptr, nullptr);
      d[1] = std::remainder(d[1], 2 * M_PI);
      CHECK((d / (2 * h) - Hx.col(c)).norm() < 1e-6);
    }
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[c] = h;
      Eigen::Vector3d d =
          SpatialEkf::observation(X, l + e, nullptr, nullptr) - SpatialEkf::observation(X, l - e, nullptr, nullptr);
      d[1] = std::remainder(d[1], 2 * M_PI);
      CHECK((d / (2 * h) - Hl.col(c)).norm() < 1e-6);
    }
    // Initialization inverts the observation, with its Jacobians.
    Eigen::Matrix<double, 3, 6> Jx;
    Eigen::Matrix3d Jz;
    CHECK((SpatialEkf::inverse_observation(X, z, &Jx, &Jz) - l).norm() < 1e-9);
    for (int c = 0; c < 6; ++c) {
      SE3::Vector6 e = SE3::Vector6::Zero();
      e[c] = h;
      const Eigen::Vector3d d = SpatialEkf::inverse_observation(X * SE3::exp(e), z, nullptr, nullptr) -
                                SpatialEkf::inverse_observation(X * SE3::exp(-e), z, nullptr, nullptr);
      CHECK((d / (2 * h) - Jx.col(c)).norm() < 1e-6);
    }
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[c] = h;
      const Eigen::Vector3d d = SpatialEkf::inverse_observation(X, z + e, nullptr, nullptr) -
                                SpatialEkf::inverse_observation(X, z - e, nullptr, nullptr);
      CHECK((d / (2 * h) - Jz.col(c)).norm() < 1e-6);
    }
  }
}

TEST_CASE("3-D EKF-SLAM: converges on a climbing circle, gates an outlier, refuses NaN, P stays SPD") {
  std::mt19937 rng(22);
  std::normal_distribution<double> n(0, 1);
  const std::vector<Eigen::Vector3d> lm = {{5, 0, 1}, {0, 5, 2}, {-5, 0, 0}, {0, -5, 3}, {3, 3, -1}, {-3, -3, 1}};
  SpatialEkf ekf;
  SE3 truth = SE3::exp((SE3::Vector6() << 2, 0, 0, 0, 0, M_PI / 2).finished());
  ekf.initialize(truth, SE3::Matrix6::Identity() * 1e-6);
  SE3::Vector6 step_xi;
  step_xi << 0.1, 0, 0.01, 0.005, 0.01, 0.05;
  const SE3 step = SE3::exp(step_xi);
  SE3::Vector6 sig;
  sig << 0.01, 0.01, 0.01, 0.003, 0.003, 0.003;
  const SE3::Matrix6 Q = sig.cwiseAbs2().asDiagonal();
  const Eigen::Matrix3d R = Eigen::Vector3d(0.01, 0.0004, 0.0004).asDiagonal();
  int accepted = 0, gated = 0;
  for (int k = 0; k < 400; ++k) {
    truth = truth * step;
    SE3::Vector6 w;
    for (int i = 0; i < 6; ++i) w[i] = sig[i] * n(rng);
    ekf.predict(step * SE3::exp(w), Q);
    for (size_t i = 0; i < lm.size(); ++i) {
      const Eigen::Vector3d z = SpatialEkf::observation(truth, lm[i], nullptr, nullptr) +
                                Eigen::Vector3d(0.1 * n(rng), 0.02 * n(rng), 0.02 * n(rng));
      accepted += ekf.observe(static_cast<int64_t>(i), z, R).accepted;
    }
    if (k % 50 == 25) gated += ekf.observe(1, Eigen::Vector3d(30, 1, 0.5), R).reason == UpdateReason::kGate;
  }
  CHECK(gated == 8);
  CHECK(accepted > 2000);
  // SLAM: the map frame is anchored at the first pose, which was known to 1 mm.
  CHECK((ekf.pose().translation() - truth.translation()).norm() < 0.2);
  CHECK((ekf.pose().inverse() * truth).log().tail<3>().norm() < 0.05);
  for (const auto& [id, p] : ekf.landmarks()) CHECK((p - lm[static_cast<size_t>(id)]).norm() < 0.3);
  const auto& P = ekf.covariance();
  CHECK((P - P.transpose()).norm() == 0.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(P);
  CHECK(eig.eigenvalues().minCoeff() > 0);
  CHECK(ekf.observe(2, Eigen::Vector3d(std::nan(""), 0, 0), R).reason == UpdateReason::kNonFinite);
  SpatialEkfOptions loc;
  loc.slam = false;
  SpatialEkf no_slam(loc);
  no_slam.initialize(SE3(), SE3::Matrix6::Identity());
  CHECK(no_slam.observe(7, Eigen::Vector3d(3, 0, 0), R).reason == UpdateReason::kUnknownLandmark);
}
