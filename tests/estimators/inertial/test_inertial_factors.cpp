// The inertial graph's factors: every Jacobian against central differences; the IMU factor's residual zero on states
// integrated independently (a plain world-frame integration written here), and small to second order in a bias
// change; the random walk's information; the GNSS factor's antenna position against the same integration, its lever
// arm, and its robust cost (e'e = rho(s), bounded pull of an outlier).
#include "estimators/inertial/inertial_factors.hpp"

#include "estimators/graph/numeric_jacobian.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>
#include <vector>

using namespace sextant;
using namespace sextant::inertial;
using sextant::test::jacobian_mismatch;

namespace {

const Eigen::Vector3d kGravity(0, 0, -9.80665);

struct Sample {
  Eigen::Vector3d w, a;  // gyroscope, specific force (IMU frame, biases included)
  double dt;
};

std::vector<Sample> random_samples(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-1, 1), dt(0.004, 0.006);
  std::vector<Sample> s;
  Eigen::Vector3d w(0.2, -0.1, 0.4), a(0.4, 0.3, 9.7);
  for (int k = 0; k < n; ++k) {
    w += 0.05 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    a += 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    s.push_back({w, a, dt(rng)});
  }
  return s;
}

// The world-frame state after the samples with the given true biases, from x0: the exact solution for
// piecewise-constant samples, integrated step by step (Rodrigues for the rotation), independent of the
// preintegration.
NavState integrate_world(const NavState& x0, const std::vector<Sample>& s, const ImuBias& b) {
  NavState x = x0;
  for (const Sample& k : s) {
    const Eigen::Vector3d acc = x.R * (k.a - b.accel) + kGravity;
    x.p += x.v * k.dt + 0.5 * acc * k.dt * k.dt;
    x.v += acc * k.dt;
    const Eigen::Vector3d phi = (k.w - b.gyro) * k.dt;
    x.R = x.R * Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
  }
  return x;
}

ImuPreintegration preintegrate(const std::vector<Sample>& s, const ImuBias& lin) {
  ImuPreintegration pim(lin);
  for (const Sample& k : s) pim.integrate(k.w, k.a, k.dt);
  return pim;
}

graph::Variable pose_variable(int64_t id, const NavState& x) {
  graph::Variable v;
  v.id = id;
  v.kind = graph::VariableKind::kPose3;
  v.pose3 = SE3(SO3(x.R), x.p);
  return v;
}

graph::Variable vector_variable(int64_t id, const Eigen::Vector3d& x) {
  graph::Variable v;
  v.id = id;
  v.kind = graph::VariableKind::kVector3;
  v.point = x;
  return v;
}

// Variables of keyframes i (0..3) and j (4, 5) in the factors' order.
std::vector<graph::Variable> keyframe_pair(const NavState& xi, const ImuBias& bi, const NavState& xj) {
  return {pose_variable(0, xi),         vector_variable(1, xi.v), vector_variable(2, bi.gyro),
          vector_variable(3, bi.accel), pose_variable(4, xj),     vector_variable(5, xj.v)};
}

const KeyframeVariables kI{0, 1, 2, 3}, kJ{4, 5, -1, -1};

NavState some_state() {
  NavState x;
  x.R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 0.9).normalized()).toRotationMatrix();
  x.v = Eigen::Vector3d(1.2, -0.4, 0.1);
  x.p = Eigen::Vector3d(3, -2, 0.5);
  return x;
}

}  // namespace

TEST_CASE("ImuFactor: zero residual on an independent world-frame integration, Jacobians against differences") {
  std::mt19937 rng(11);
  const auto samples = random_samples(rng, 200);  // 1 s
  ImuBias truth;
  truth.gyro = Eigen::Vector3d(0.01, -0.02, 0.015);
  truth.accel = Eigen::Vector3d(0.1, 0.05, -0.08);
  const NavState xi = some_state();
  const NavState xj = integrate_world(xi, samples, truth);

  // Preintegrated at the true bias: the residual vanishes to rounding.
  const ImuFactor exact(kI, kJ, preintegrate(samples, truth), kGravity);
  Eigen::VectorXd e(9);
  exact.error(keyframe_pair(xi, truth, xj), e);
  CHECK(e.norm() < 1e-9);

  // Preintegrated at a bias 0.005 rad/s, 0.05 m/s^2 off: the first-order correction leaves a residual of second
  // order; uncorrected (evaluated at the linearisation point) the residual is first order.
  ImuBias lin = truth;
  lin.gyro += Eigen::Vector3d(0.005, -0.004, 0.003);
  lin.accel += Eigen::Vector3d(-0.05, 0.04, 0.03);
  const ImuFactor off(kI, kJ, preintegrate(samples, lin), kGravity);
  Eigen::VectorXd corrected(9), uncorrected(9);
  off.error(keyframe_pair(xi, truth, xj), corrected);
  off.error(keyframe_pair(xi, lin, xj), uncorrected);
  MESSAGE("bias 5e-3 rad/s, 5e-2 m/s^2 off: residual corrected ", corrected.norm(), ", uncorrected ",
          uncorrected.norm());
  CHECK(corrected.norm() < 0.02 * uncorrected.norm());

  // Jacobians at states away from consistency and a bias away from the linearisation point.
  NavState xj_off = xj;
  xj_off.p += Eigen::Vector3d(0.3, -0.2, 0.1);
  xj_off.v += Eigen::Vector3d(-0.1, 0.2, 0.05);
  xj_off.R = xj_off.R * Eigen::AngleAxisd(0.1, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  CHECK(jacobian_mismatch(off, keyframe_pair(xi, truth, xj_off)) < 1e-6);
  CHECK(jacobian_mismatch(exact, keyframe_pair(xi, truth, xj)) < 1e-6);
  // Information: the preintegrated covariance's inverse.
  CHECK((off.information() * off.preintegration().covariance() - Eigen::MatrixXd::Identity(9, 9)).norm() < 1e-6);
}

TEST_CASE("ImuFactor: an empty preintegration is refused") {
  CHECK_THROWS_AS(ImuFactor(kI, kJ, ImuPreintegration(), kGravity), std::invalid_argument);
}

TEST_CASE("RandomWalkFactor: e = b_j - b_i with information 1 / (density^2 dt), exact Jacobians") {
  const RandomWalkFactor f(0, 1, 2e-3, 0.5);
  const std::vector<graph::Variable> v = {vector_variable(0, Eigen::Vector3d(0.1, 0.2, 0.3)),
                                          vector_variable(1, Eigen::Vector3d(0.2, 0.1, 0.3))};
  Eigen::VectorXd e(3);
  f.error(v, e);
  CHECK((e - Eigen::Vector3d(0.1, -0.1, 0)).norm() < 1e-15);
  CHECK(f.information()(0, 0) == doctest::Approx(1 / (4e-6 * 0.5)));
  CHECK(jacobian_mismatch(f, v) < 1e-8);
  CHECK_THROWS_AS(RandomWalkFactor(0, 1, 0, 1), std::invalid_argument);
  CHECK_THROWS_AS(RandomWalkFactor(0, 1, 1, std::nan("")), std::invalid_argument);
}

TEST_CASE("GnssPositionFactor: the antenna after the motion since the keyframe, lever arm, exact Jacobians") {
  std::mt19937 rng(5);
  const auto samples = random_samples(rng, 60);  // 0.3 s after the keyframe
  ImuBias truth;
  truth.gyro = Eigen::Vector3d(0.01, -0.02, 0.015);
  truth.accel = Eigen::Vector3d(0.1, 0.05, -0.08);
  const NavState xi = some_state();
  const NavState xt = integrate_world(xi, samples, truth);
  const Eigen::Vector3d lever(0.2, -0.1, 0.8);
  const Eigen::Vector3d antenna = xt.p + xt.R * lever;  // where the fix is, computed independently
  Eigen::Matrix3d S = Eigen::Vector3d(0.25, 0.25, 1.0).asDiagonal();
  S(0, 1) = S(1, 0) = 0.05;
  ImuBias lin = truth;
  lin.gyro += Eigen::Vector3d(0.004, 0.002, -0.003);
  const auto vars = keyframe_pair(xi, truth, xi);

  for (auto kernel : {graph::RobustKernel::kNone, graph::RobustKernel::kHuber, graph::RobustKernel::kCauchy}) {
    CAPTURE(graph::robust_kernel_name(kernel));
    const GnssPositionFactor at_truth(kI, preintegrate(samples, truth), kGravity, antenna, S, lever, kernel, 2.8);
    Eigen::VectorXd e(3);
    at_truth.error(vars, e);
    CHECK(e.norm() < 1e-9);
    CHECK(at_truth.predicted(vars).isApprox(antenna, 1e-12));
    // Jacobians for an inlier (s < width^2) and an outlier (10 m off), with a bias off the linearisation point.
    for (double off : {0.3, 10.0}) {
      const GnssPositionFactor f(kI, preintegrate(samples, lin), kGravity, antenna + Eigen::Vector3d(off, -off, 0.1), S,
                                 lever, kernel, 2.8);
      CHECK(jacobian_mismatch(f, vars) < 1e-6);
      f.error(vars, e);
      const double s = f.squared_error(vars);
      CHECK(e.squaredNorm() == doctest::Approx(graph::robust_cost(kernel, 2.8, s)).epsilon(1e-12));
    }
  }
  // At the keyframe's own time (no preintegration): p + R l.
  const GnssPositionFactor plain(0, xi.p + xi.R * lever, S, lever, graph::RobustKernel::kHuber, 2.8);
  Eigen::VectorXd e(3);
  plain.error(vars, e);
  CHECK(e.norm() < 1e-12);
  std::vector<graph::Variable> moved = vars;
  moved[0].pose3 = moved[0].pose3 * SE3::exp((Vector6d() << 0.2, 0.1, -0.3, 0.05, -0.1, 0.2).finished());
  CHECK(jacobian_mismatch(plain, moved) < 1e-6);
  CHECK_THROWS_AS(GnssPositionFactor(0, antenna, -S, lever, graph::RobustKernel::kNone, 1), std::invalid_argument);
  CHECK_THROWS_AS(GnssPositionFactor(0, antenna, S, lever, graph::RobustKernel::kHuber, 0), std::invalid_argument);
}

TEST_CASE("GnssPositionFactor: the gradient of an outlier is bounded by the kernel, an inlier's is not changed") {
  const NavState xi = some_state();
  const auto vars = keyframe_pair(xi, ImuBias{}, xi);
  const Eigen::Matrix3d S = Eigen::Matrix3d::Identity() * 0.25;  // 0.5 m
  // Gradient J'e of the cost with respect to the position (the pose's rho), for fixes d metres east of the body.
  auto pull = [&](double d, graph::RobustKernel k) {
    const GnssPositionFactor f(0, xi.p + Eigen::Vector3d(d, 0, 0), S, Eigen::Vector3d::Zero(), k, 2.8);
    graph::Linearization l = f.make_linearization(vars);
    f.linearize(vars, l);
    return (l.jacobians[0].leftCols<3>().transpose() * l.error).norm();
  };
  CHECK(pull(0.5, graph::RobustKernel::kHuber) == doctest::Approx(pull(0.5, graph::RobustKernel::kNone)));
  // Plain least squares pulls 20 times harder at 10 m than at 0.5 m; Huber's pull stops growing past its width
  // (2.8 sigma = 1.4 m), Cauchy's falls.
  CHECK(pull(10, graph::RobustKernel::kNone) == doctest::Approx(20 * pull(0.5, graph::RobustKernel::kNone)));
  CHECK(pull(10, graph::RobustKernel::kHuber) == doctest::Approx(pull(2, graph::RobustKernel::kHuber)).epsilon(1e-6));
  CHECK(pull(10, graph::RobustKernel::kCauchy) < pull(2, graph::RobustKernel::kCauchy));
}
