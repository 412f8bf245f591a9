// Dead reckoning against independent computations: poses composed by hand, covariance by numerical Jacobians of
// the composition (first-order propagation computed without the adjoint formula the stage uses).
#include "daemon/engine/dead_reckoning_stage.hpp"

#include <doctest/doctest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>
#include <vector>

using namespace sextant::engine;

namespace {

Eigen::Isometry3d iso(const Pose& p) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = p.orientation.toRotationMatrix();
  x.translation() = p.position;
  return x;
}

Pose pose_of(const Eigen::Isometry3d& x) {
  Pose p;
  p.position = x.translation();
  p.orientation = Eigen::Quaterniond(x.linear());
  return p;
}

// exp of se(3) for small perturbations, written independently: rotation by angle-axis, translation by V(phi)*rho.
Eigen::Isometry3d exp6(const Eigen::Matrix<double, 6, 1>& xi) {
  const Eigen::Vector3d rho = xi.head<3>(), phi = xi.tail<3>();
  const double th = phi.norm();
  Eigen::Matrix3d K;
  K << 0, -phi.z(), phi.y(), phi.z(), 0, -phi.x(), -phi.y(), phi.x(), 0;
  Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  if (th > 1e-12) {
    R = Eigen::AngleAxisd(th, phi / th).toRotationMatrix();
    V += (1 - std::cos(th)) / (th * th) * K + (th - std::sin(th)) / (th * th * th) * K * K;
  }
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = R;
  x.translation() = V * rho;
  return x;
}

// log of a near-identity isometry: rotation vector from angle-axis, translation solved through V.
Eigen::Matrix<double, 6, 1> log6(const Eigen::Isometry3d& x) {
  const Eigen::AngleAxisd aa(x.linear());
  const Eigen::Vector3d phi = aa.axis() * aa.angle();
  const double th = phi.norm();
  Eigen::Matrix3d K;
  K << 0, -phi.z(), phi.y(), phi.z(), 0, -phi.x(), -phi.y(), phi.x(), 0;
  Eigen::Matrix3d V = Eigen::Matrix3d::Identity();
  if (th > 1e-12) V += (1 - std::cos(th)) / (th * th) * K + (th - std::sin(th)) / (th * th * th) * K * K;
  Eigen::Matrix<double, 6, 1> xi;
  xi << V.inverse() * x.translation(), phi;
  return xi;
}

Odometry odom(int64_t utime, const Eigen::Isometry3d& pose, const Matrix6& cov, const Matrix6& inc, bool planar) {
  Odometry o;
  o.utime = utime;
  o.source = "r";
  o.planar = planar;
  o.pose = pose_of(pose);
  o.covariance = cov;
  o.increment_covariance = inc;
  return o;
}

}  // namespace

TEST_CASE("a planar square: four quarter turns return to the start, poses match the hand composition") {
  DeadReckoningConfig cfg;
  cfg.min_increment_variance = 0;
  DeadReckoningStage stage(cfg);
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  Matrix6 q = Matrix6::Zero();
  q(0, 0) = q(1, 1) = 0.01;
  q(5, 5) = 0.001;
  // The odometry frame starts at (5, 0) facing +y; each step drives 1 m and turns left 90 degrees.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(5, 0, 0);
  T.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation() = Eigen::Vector3d(1, 0, 0);
  step.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int k = 0; k <= 4; ++k) {
    stage.handle(odom(1000 + k, T, q, q, true), emit);
    T = T * step;
  }
  REQUIRE(out.size() == 5);
  // By hand: (5,0) -> (5,1) -> (4,1) -> (4,0) -> (5,0), heading +y, -x, -y, +x, +y.
  const double expected[5][2] = {{5, 0}, {5, 1}, {4, 1}, {4, 0}, {5, 0}};
  for (int k = 0; k < 5; ++k) {
    CHECK(out[k].pose.position.x() == doctest::Approx(expected[k][0]).epsilon(1e-12));
    CHECK(out[k].pose.position.y() == doctest::Approx(expected[k][1]).epsilon(1e-12));
    CHECK(out[k].estimator == "dead_reckoning");
    CHECK(out[k].utime == 1000 + k);
  }
  // The covariance grows (uncertainty never shrinks without measurements) and z, roll, pitch stay exactly zero.
  for (int k = 1; k < 5; ++k) {
    CHECK(out[k].covariance(0, 0) + out[k].covariance(1, 1) >
          out[k - 1].covariance(0, 0) + out[k - 1].covariance(1, 1));
    CHECK(out[k].covariance(2, 2) == 0.0);
    CHECK(out[k].covariance(3, 3) == 0.0);
  }
  // Heading variance of a planar chain adds up exactly: 5 x 0.001.
  CHECK(out[4].covariance(5, 5) == doctest::Approx(0.005));
}

TEST_CASE("3D covariance propagation equals numerically linearized composition") {
  // P_k = J_prev P J_prev^T + J_inc Q J_inc^T with J by central differences of
  // xi -> log((M Delta)^-1 * M exp(xi) Delta exp(eta)).
  Eigen::Isometry3d M = Eigen::Isometry3d::Identity();
  M.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, -0.5, 1).normalized()).toRotationMatrix();
  M.translation() = Eigen::Vector3d(1, 2, 3);
  Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
  D.linear() = Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 1, 0.3).normalized()).toRotationMatrix();
  D.translation() = Eigen::Vector3d(0.7, -0.3, 0.2);
  Matrix6 A, B;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      A(i, j) = std::cos(i + 2.0 * j);
      B(i, j) = std::sin(3.0 * i - j);
    }
  const Matrix6 P = 0.01 * (A * A.transpose() + Matrix6::Identity());
  const Matrix6 Q = 0.002 * (B * B.transpose() + Matrix6::Identity());

  const Eigen::Isometry3d nominal = M * D;
  Matrix6 J_prev, J_inc;
  const double h = 1e-6;
  for (int c = 0; c < 6; ++c) {
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    e[c] = h;
    J_prev.col(c) = (log6(nominal.inverse() * M * exp6(e) * D) - log6(nominal.inverse() * M * exp6(-e) * D)) / (2 * h);
    J_inc.col(c) = (log6(nominal.inverse() * M * D * exp6(e)) - log6(nominal.inverse() * M * D * exp6(-e))) / (2 * h);
  }
  const Matrix6 expected = J_prev * P * J_prev.transpose() + J_inc * Q * J_inc.transpose();

  DeadReckoningConfig cfg;
  cfg.min_increment_variance = 0;
  DeadReckoningStage stage(cfg);
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  stage.handle(odom(1, M, P, Q, false), emit);
  stage.handle(odom(2, M * D, P, Q, false), emit);
  REQUIRE(out.size() == 2);
  CHECK((out[1].covariance - expected).norm() < 1e-6 * expected.norm());
  CHECK((iso(out[1].pose).matrix() - nominal.matrix()).norm() < 1e-12);
}

TEST_CASE("without increment covariance, the growth of the pose covariance is used (differential mode)") {
  DeadReckoningConfig cfg;
  cfg.min_increment_variance = 0;
  DeadReckoningStage stage(cfg);
  std::vector<FusedPose> out;
  const Emit emit = [&](Output o) { out.push_back(std::get<FusedPose>(o)); };
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  // Turning on the spot: the adjoint is a rotation, which maps an isotropic covariance onto itself, so the
  // difference of the sender's covariances is exactly the 0.01 I it added.
  step.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Matrix6 cov = Matrix6::Identity() * 0.01;
  for (int k = 0; k < 3; ++k) {
    Odometry o = odom(10 + k, T, cov, cov, false);
    o.increment_covariance.reset();
    stage.handle(o, emit);
    T = T * step;
    cov += Matrix6::Identity() * 0.01;  // the sender's covariance grows by 0.01 per step in every component
  }
  REQUIRE(out.size() == 3);
  // 0.01 initial + 0.01 per step, in every component.
  CHECK((out[2].covariance - Matrix6::Identity() * 0.03).norm() < 1e-12);
  // The result stays symmetric positive definite.
  Eigen::SelfAdjointEigenSolver<Matrix6> eig(out[2].covariance);
  CHECK(eig.eigenvalues().minCoeff() > 0);
  CHECK((out[2].covariance - out[2].covariance.transpose()).norm() == 0.0);
}

TEST_CASE("sources are independent and a long gap is counted") {
  DeadReckoningStage stage(DeadReckoningConfig{});
  int n = 0;
  const Emit emit = [&](Output) { ++n; };
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Odometry a = odom(1'000'000, T, Matrix6::Identity(), Matrix6::Identity(), false);
  Odometry b = a;
  b.source = "other";
  stage.handle(a, emit);
  stage.handle(b, emit);
  a.utime = 5'000'000;  // 4 s later
  stage.handle(a, emit);
  CHECK(n == 3);
  const auto c = stage.counters();
  CHECK(c.at(1).first == "odometry_gaps");
  CHECK(c.at(1).second == 1);
  CHECK(c.at(2).second == 2);
}
