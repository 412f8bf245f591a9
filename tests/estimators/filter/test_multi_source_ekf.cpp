// Several odometry sources of one body: the EKF's covariance against an independent information-form (batch,
// linearized) computation, component masks, the rejection gate, timeouts, the pose-measurement Jacobians.
#include "estimators/filter/multi_source_ekf.hpp"

#include <doctest/doctest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <random>

using namespace sextant;
using namespace sextant::filter;

namespace {

Eigen::Vector3d vec(const SE2& x) { return {x.translation().x(), x.translation().y(), x.angle()}; }
SE2 pose(const Eigen::Vector3d& v) { return SE2(v[0], v[1], v[2]); }

// A factor of the batch problem: residual Log(Z^-1 A^-1 X_j) (A = X_i, or the fixed `frame` when i < 0).
struct Factor {
  int i, j;
  SE2 z, frame;
  Eigen::Matrix3d R;
  std::array<bool, 3> rows{true, true, true};
};

Eigen::Vector3d residual(const Factor& f, const std::vector<Eigen::Vector3d>& x) {
  const SE2 a = f.i < 0 ? f.frame : pose(x[static_cast<size_t>(f.i)]);
  return (f.z.inverse() * a.inverse() * pose(x[static_cast<size_t>(f.j)])).log();
}

// Marginal covariance of the last pose: information matrix from a prior on x0 and every factor's Jacobian (central
// differences), inverted.
Eigen::Matrix3d batch_marginal(const std::vector<Eigen::Vector3d>& x, const Eigen::Matrix3d& P0,
                               const std::vector<Factor>& factors) {
  const auto n = static_cast<Eigen::Index>(3 * x.size());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  L.topLeftCorner<3, 3>() = P0.inverse();
  for (const auto& f : factors) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n);
    for (Eigen::Index c = 0; c < n; ++c) {
      auto xp = x, xm = x;
      xp[static_cast<size_t>(c / 3)][c % 3] += 1e-6;
      xm[static_cast<size_t>(c / 3)][c % 3] -= 1e-6;
      J.col(c) = (residual(f, xp) - residual(f, xm)) / 2e-6;
    }
    std::vector<int> use;
    for (int r = 0; r < 3; ++r)
      if (f.rows[static_cast<size_t>(r)]) use.push_back(r);
    Eigen::MatrixXd Jm(use.size(), n), Rm(use.size(), use.size());
    for (size_t a = 0; a < use.size(); ++a) {
      Jm.row(static_cast<Eigen::Index>(a)) = J.row(use[a]);
      for (size_t b = 0; b < use.size(); ++b)
        Rm(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = f.R(use[a], use[b]);
    }
    L += Jm.transpose() * Rm.inverse() * Jm;
  }
  return L.inverse().bottomRightCorner<3, 3>();
}

// The true poses of a curving run, 10 steps of 0.1 s.
std::vector<SE2> truth_run() {
  std::vector<SE2> x{SE2(1, 2, 0.3)};
  for (int k = 1; k <= 10; ++k) x.push_back(x.back() * SE2(0.2, 0.01 * k, 0.08 - 0.01 * k));
  return x;
}

PlanarOdometry reading(int k, const SE2& p, const Eigen::Matrix3d& pose_cov,
                       const std::optional<Eigen::Matrix3d>& inc) {
  PlanarOdometry m;
  m.utime = 1'000'000 + 100'000 * k;
  m.pose = p;
  m.covariance = pose_cov;
  m.increment_covariance = inc;
  return m;
}

const Eigen::Matrix3d kP0 = Eigen::Vector3d(1e-4, 2e-4, 1e-5).asDiagonal();
const Eigen::Matrix3d kQw = Eigen::Vector3d(4e-4, 1e-4, 2e-4).asDiagonal();

}  // namespace

TEST_CASE("pose-measurement innovations: Jacobians against central differences") {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng)), x(u(rng), u(rng), u(rng));
    const SE2 z = pose(c).between(pose(x)) * SE2(0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
    const SE2 frame(u(rng), u(rng), u(rng));
    Eigen::Matrix3d Hc, Hx, Ha;
    PlanarEkf::relative_pose_innovation(c, x, z, &Hc, &Hx);
    PlanarEkf::pose_innovation(frame, x, frame.inverse() * pose(x) * SE2(0.1, -0.1, 0.2), &Ha);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[k] = 1e-6;
      const Eigen::Vector3d dc = PlanarEkf::relative_pose_innovation(c + e, x, z, nullptr, nullptr) -
                                 PlanarEkf::relative_pose_innovation(c - e, x, z, nullptr, nullptr);
      const Eigen::Vector3d dx = PlanarEkf::relative_pose_innovation(c, x + e, z, nullptr, nullptr) -
                                 PlanarEkf::relative_pose_innovation(c, x - e, z, nullptr, nullptr);
      const SE2 za = frame.inverse() * pose(x) * SE2(0.1, -0.1, 0.2);
      const Eigen::Vector3d da =
          PlanarEkf::pose_innovation(frame, x + e, za, nullptr) - PlanarEkf::pose_innovation(frame, x - e, za, nullptr);
      CHECK((-dc / 2e-6 - Hc.col(k)).norm() < 1e-6);
      CHECK((-dx / 2e-6 - Hx.col(k)).norm() < 1e-6);
      CHECK((-da / 2e-6 - Ha.col(k)).norm() < 1e-6);
    }
  }
}

TEST_CASE("two odometry sources: the EKF covariance equals the information-form marginal") {
  const auto X = truth_run();
  std::vector<Eigen::Vector3d> xv;
  for (const auto& x : X) xv.push_back(vec(x));
  const SE2 G(5, -3, 1.0);  // the second source's frame: it reports G * X
  const Eigen::Matrix3d Qv = Eigen::Vector3d(1e-4, 9e-4, 5e-5).asDiagonal();
  const Eigen::Matrix3d Rabs = Eigen::Vector3d(2e-3, 1e-3, 4e-4).asDiagonal();
  const Eigen::Matrix3d Sv = Eigen::Vector3d(0.01, 0.04, 0.002).asDiagonal();  // twist covariance

  struct Case {
    std::string name;
    OdometrySourceOptions vo;
  };
  OdometrySourceOptions full, yaw_only, absolute_xy, velocity;
  yaw_only.fuse = {false, false, true, false, false, false};
  absolute_xy.fuse = {true, true, false, false, false, false};
  absolute_xy.differential = false;
  velocity.fuse = {false, false, false, true, false, true};
  // Twists whose mean over each step integrates to the true increment: (v_{k-1} + v_k) / 2 * dt = Log(X_{k-1}^-1 X_k).
  std::vector<Eigen::Vector3d> twists{X[0].between(X[1]).log() / 0.1};
  for (size_t k = 1; k < X.size(); ++k) twists.push_back(2 * X[k - 1].between(X[k]).log() / 0.1 - twists.back());
  for (const Case& cs : {Case{"differential x y yaw", full}, Case{"differential yaw only", yaw_only},
                         Case{"absolute x y", absolute_xy}, Case{"velocities vx vyaw", velocity}}) {
    CAPTURE(cs.name);
    OdometrySourceOptions wheel;
    wheel.predict = true;
    MultiSourceEkf ekf(PlanarEkfOptions{}, kP0, {{"wheel", wheel}, {"vo", cs.vo}});
    std::vector<Factor> factors;
    const std::array<bool, 3> pose_rows{cs.vo.fuse[0], cs.vo.fuse[1], cs.vo.fuse[2]};
    const std::array<bool, 3> vel_rows{cs.vo.fuse[3], cs.vo.fuse[4], cs.vo.fuse[5]};
    for (int k = 0; k < static_cast<int>(X.size()); ++k) {
      const auto K = static_cast<size_t>(k);
      CHECK(ekf.odometry("wheel", reading(k, X[K], Eigen::Matrix3d::Zero(), kQw)) ==
            (k == 0 ? OdometryOutcome::initialized : OdometryOutcome::predicted));
      PlanarOdometry v = reading(k, G * X[K], Rabs, Qv);
      v.twist = twists[K];
      v.twist_covariance = Sv;
      const auto out = ekf.odometry("vo", v);
      CHECK(out == (k == 0 ? OdometryOutcome::anchored : OdometryOutcome::fused));
      if (k == 0) continue;
      factors.push_back({k - 1, k, X[K - 1].between(X[K]), SE2(), kQw});
      if (cs.vo.differential && (pose_rows[0] || pose_rows[1] || pose_rows[2]))
        factors.push_back({k - 1, k, X[K - 1].between(X[K]), SE2(), Qv, pose_rows});
      if (!cs.vo.differential) factors.push_back({-1, k, G * X[K], G.inverse(), Rabs, pose_rows});
      if (vel_rows[0] || vel_rows[2])
        factors.push_back({k - 1, k, X[K - 1].between(X[K]), SE2(), Sv * 0.1 * 0.1, vel_rows});
    }
    const Eigen::Matrix3d batch = batch_marginal(xv, kP0, factors);
    const Eigen::Matrix3d P = ekf.ekf().pose_covariance();
    MESSAGE(cs.name << ": EKF var " << P.diagonal().transpose() << ", batch " << batch.diagonal().transpose());
    CHECK((P - batch).norm() < 1e-6 * batch.norm());
    CHECK((vec(ekf.ekf().pose()) - xv.back()).norm() < 1e-9);
    // The second source helped: smaller than wheel odometry alone in the fused components.
    MultiSourceEkf alone(PlanarEkfOptions{}, kP0, {{"wheel", wheel}});
    for (int k = 0; k < static_cast<int>(X.size()); ++k)
      alone.odometry("wheel", reading(k, X[static_cast<size_t>(k)], Eigen::Matrix3d::Zero(), kQw));
    CHECK(P.determinant() < alone.ekf().pose_covariance().determinant());
  }
}

TEST_CASE("two odometry sources: the gate rejects an outlier, a silent source times out once and re-anchors") {
  const auto X = truth_run();
  OdometrySourceOptions wheel, vo;
  wheel.predict = true;
  vo.gate = 11.34;  // chi-square 3 dof, 99 %
  vo.timeout_s = 0.25;
  MultiSourceEkf ekf(PlanarEkfOptions{}, kP0, {{"wheel", wheel}, {"vo", vo}});
  const Eigen::Matrix3d Qv = Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal();
  for (int k = 0; k <= 3; ++k) {
    ekf.odometry("wheel", reading(k, X[static_cast<size_t>(k)], Eigen::Matrix3d::Zero(), kQw));
    SE2 z = X[static_cast<size_t>(k)];
    if (k == 3) z = z * SE2(1.0, 0, 0);  // a 1 m jump
    const Eigen::VectorXd before = ekf.ekf().state().head<3>();
    const Eigen::Matrix3d P_before = ekf.ekf().pose_covariance();
    const auto out = ekf.odometry("vo", reading(k, z, Eigen::Matrix3d::Zero(), Qv));
    if (k == 3) {
      CHECK(out == OdometryOutcome::gated);
      CHECK(ekf.ekf().state().head<3>() == before);
      CHECK(ekf.ekf().pose_covariance() == P_before);
    }
  }
  CHECK(ekf.counters().at("vo").fused == 2);
  CHECK(ekf.counters().at("vo").gated == 1);
  // Duplicate stamp.
  CHECK(ekf.odometry("vo", reading(3, X[3], Eigen::Matrix3d::Zero(), Qv)) == OdometryOutcome::duplicate);
  // vo falls silent from k = 3 (t = 1.3 s); the wheel goes on: at k = 6 (0.3 s later) the timeout is reported, once.
  for (int k = 4; k <= 8; ++k)
    ekf.odometry("wheel", reading(k, X[static_cast<size_t>(k)], Eigen::Matrix3d::Zero(), kQw));
  CHECK(ekf.counters().at("vo").timeouts == 1);
  CHECK(ekf.counters().at("vo").silent);
  // It comes back: the first message re-anchors (the gap is not fused), the next one is fused again.
  CHECK(ekf.odometry("vo", reading(8, SE2(0.5, 0.5, 0.5) * X[8], Eigen::Matrix3d::Zero(), Qv)) ==
        OdometryOutcome::anchored);
  CHECK_FALSE(ekf.counters().at("vo").silent);
  ekf.odometry("wheel", reading(9, X[9], Eigen::Matrix3d::Zero(), kQw));
  CHECK(ekf.odometry("vo", reading(9, SE2(0.5, 0.5, 0.5) * X[9], Eigen::Matrix3d::Zero(), Qv)) ==
        OdometryOutcome::fused);
  CHECK(ekf.counters().at("vo").timeouts == 1);
  // Non-finite increment covariance: refused, counted.
  ekf.odometry("wheel", reading(10, X[10], Eigen::Matrix3d::Zero(), kQw));
  Eigen::Matrix3d bad = Qv;
  bad(0, 0) = std::nan("");
  CHECK(ekf.odometry("vo", reading(10, SE2(0.5, 0.5, 0.5) * X[10], Eigen::Matrix3d::Zero(), bad)) ==
        OdometryOutcome::rejected);
  CHECK(ekf.odometry("other", reading(10, X[10], Eigen::Matrix3d::Zero(), Qv)) == OdometryOutcome::unknown_source);
}

TEST_CASE("odometry source configuration errors") {
  OdometrySourceOptions p, m;
  p.predict = true;
  CHECK_THROWS_AS(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", m}}), std::invalid_argument);
  CHECK_THROWS_AS(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", p}, {"b", p}}), std::invalid_argument);
  auto none = m;
  none.fuse = {false, false, false, false, false, false};
  CHECK_THROWS_AS(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", p}, {"b", none}}), std::invalid_argument);
  auto twice = m;
  twice.fuse = {true, true, true, true, false, false};
  CHECK_THROWS_AS(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", p}, {"b", twice}}), std::invalid_argument);
  auto masked_predict = p;
  masked_predict.fuse = {true, true, false, false, false, false};
  CHECK_THROWS_AS(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", masked_predict}}), std::invalid_argument);
  CHECK_NOTHROW(MultiSourceEkf(PlanarEkfOptions{}, kP0, {{"a", p}, {"b", m}}));
}

TEST_CASE("a prediction split at stops reaches the same pose, with the stops at the interpolated poses") {
  OdometrySourceOptions wheel;
  wheel.predict = true;
  MultiSourceEkf split(PlanarEkfOptions{}, kP0, {{"wheel", wheel}}), whole(PlanarEkfOptions{}, kP0, {{"wheel", wheel}});
  const SE2 a(1, 2, 0.3), b = a * SE2(0.04, 0.002, 0.02);  // one 20 ms step of a 2 m/s robot
  split.odometry("wheel", reading(0, a, Eigen::Matrix3d::Zero(), kQw));
  whole.odometry("wheel", reading(0, a, Eigen::Matrix3d::Zero(), kQw));
  std::vector<SE2> at;
  // reading(1) is 100 ms later: stops at 25 and 75 ms, one outside the interval, one repeated.
  const std::vector<int64_t> stops{1'000'000 + 25'000, 1'000'000 + 25'000, 1'000'000 + 75'000, 1'000'000 + 200'000};
  std::vector<size_t> called;
  split.odometry("wheel", reading(1, b, Eigen::Matrix3d::Zero(), kQw), stops, [&](size_t i) {
    called.push_back(i);
    at.push_back(split.ekf().pose());
  });
  whole.odometry("wheel", reading(1, b, Eigen::Matrix3d::Zero(), kQw));
  CHECK(called == std::vector<size_t>{0, 1, 2});
  CHECK((vec(split.ekf().pose()) - vec(whole.ekf().pose())).norm() < 1e-12);
  const Eigen::Vector3d tau = a.between(b).log();
  CHECK((vec(at[0]) - vec(a * SE2::exp(0.25 * tau))).norm() < 1e-12);
  CHECK((vec(at[2]) - vec(a * SE2::exp(0.75 * tau))).norm() < 1e-12);
  // The noise is split in proportion (accumulated along the path rather than at the end): the same to first order.
  const Eigen::Matrix3d Ps = split.ekf().pose_covariance(), Pw = whole.ekf().pose_covariance();
  MESSAGE("split/whole covariance difference " << (Ps - Pw).norm() / Pw.norm());
  CHECK((Ps - Pw).norm() < 0.01 * Pw.norm());
}

TEST_CASE("odometry noise that is not positive definite is repaired, so P stays symmetric positive definite") {
  OdometrySourceOptions wheel, vo;
  wheel.predict = true;
  MultiSourceEkf ekf(PlanarEkfOptions{}, kP0, {{"wheel", wheel}, {"vo", vo}}, 1e-10);
  const auto X = truth_run();
  Eigen::Matrix3d bad;  // symmetric with a negative eigenvalue, and an asymmetric part
  bad << 1e-4, 2e-4, 0, 2e-4, 1e-4, 0, 1e-5, 0, -1e-6;
  for (int k = 0; k < 5; ++k) {
    ekf.odometry("wheel", reading(k, X[static_cast<size_t>(k)], Eigen::Matrix3d::Zero(), bad));
    ekf.odometry("vo", reading(k, X[static_cast<size_t>(k)], Eigen::Matrix3d::Zero(), bad));
  }
  CHECK(ekf.counters().at("vo").fused == 4);
  const Eigen::MatrixXd& P = ekf.ekf().covariance();
  CHECK((P - P.transpose()).norm() == 0.0);
  // The clone of a differential source equals the pose right after each message: the full P is positive
  // semi-definite by construction (rounding aside); the pose block is positive definite.
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(P);
  CHECK(eig.eigenvalues().minCoeff() > -1e-15);
  CHECK(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ekf.ekf().pose_covariance()).eigenvalues().minCoeff() > 0);
  const Eigen::Matrix3d Q = MultiSourceEkf::increment_noise(reading(0, X[0], Eigen::Matrix3d::Zero(), std::nullopt),
                                                            reading(1, X[1], Eigen::Matrix3d::Zero(), bad), 1e-10);
  CHECK((Q - Q.transpose()).norm() == 0.0);
  CHECK(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(Q).eigenvalues().minCoeff() >= 1e-10 * 0.999);
}
