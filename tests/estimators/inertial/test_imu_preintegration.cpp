// IMU preintegration: equal to a plain world-frame integration written here (1e-9); the bias Jacobians and the
// error propagation (A, B, C) against central differences; the first-order bias correction against re-integration;
// the covariance against a Monte Carlo run; and on 40 s of EuRoC V1_02 with the true biases against Vicon truth.
#include "estimators/inertial/imu_preintegration.hpp"
#include "estimators/inertial/euroc_excerpt.hpp"

#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace sextant::inertial;
using sextant::test::EurocExcerpt;

namespace {

struct Sample {
  Eigen::Vector3d w, a;
  double dt;
};

// Rodrigues' formula, written here rather than taken from estimators/lie so the comparison is independent.
Eigen::Matrix3d rodrigues(const Eigen::Vector3d& phi) {
  const double t = phi.norm();
  if (t < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(t, phi / t).toRotationMatrix();
}

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

std::vector<Sample> random_samples(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> u(-1, 1), dt(0.002, 0.008);
  std::vector<Sample> s;
  Eigen::Vector3d w(0.3, -0.2, 0.5), a(0.5, 0.2, 9.8);
  for (int k = 0; k < n; ++k) {
    w += 0.05 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    a += 0.2 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    s.push_back({w, a, dt(rng)});
  }
  return s;
}

ImuPreintegration preintegrate(const std::vector<Sample>& s, const ImuBias& b, const ImuNoise& noise = {}) {
  ImuPreintegration pim(b, noise);
  for (const Sample& x : s) pim.integrate(x.w, x.a, x.dt);
  return pim;
}

}  // namespace

TEST_CASE("preintegration equals a straightforward world-frame integration (1e-9)") {
  std::mt19937 rng(3);
  const std::vector<Sample> samples = random_samples(rng, 400);
  ImuBias b;
  b.gyro = Eigen::Vector3d(0.01, -0.02, 0.005);
  b.accel = Eigen::Vector3d(0.1, 0.05, -0.2);
  const Eigen::Vector3d g(0, 0, -9.81);
  // The world-frame state from an arbitrary start, each sample held constant over its dt.
  Eigen::Matrix3d R = rodrigues(Eigen::Vector3d(0.4, -1.1, 2.0));
  Eigen::Vector3d v(1, -2, 0.5), p(10, 20, -3);
  const Eigen::Matrix3d R0 = R;
  const Eigen::Vector3d v0 = v, p0 = p;
  double T = 0;
  for (const Sample& s : samples) {
    const Eigen::Vector3d a_world = R * (s.a - b.accel) + g;
    p = p + v * s.dt + 0.5 * a_world * s.dt * s.dt;
    v = v + a_world * s.dt;
    R = R * rodrigues((s.w - b.gyro) * s.dt);
    T += s.dt;
  }
  const ImuPreintegration pim = preintegrate(samples, b);
  CHECK(std::abs(pim.dt() - T) < 1e-12);
  CHECK((pim.delta_R() - R0.transpose() * R).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((pim.delta_v() - R0.transpose() * (v - v0 - g * T)).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((pim.delta_p() - R0.transpose() * (p - p0 - v0 * T - 0.5 * g * T * T)).cwiseAbs().maxCoeff() < 1e-9);
  // And the state prediction of eq. 38 reproduces the integrated state.
  NavState i;
  i.R = R0, i.v = v0, i.p = p0;
  const NavState j = pim.predict(i, b, g);
  CHECK((j.R - R).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((j.v - v).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((j.p - p).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("preintegration bias Jacobians against central differences of re-integration") {
  std::mt19937 rng(5);
  const std::vector<Sample> samples = random_samples(rng, 200);
  const ImuBias b0;
  const ImuPreintegration pim = preintegrate(samples, b0);
  const double h = 1e-6;
  for (int c = 0; c < 6; ++c) {
    ImuBias plus = b0, minus = b0;
    (c < 3 ? plus.gyro : plus.accel)(c % 3) += h;
    (c < 3 ? minus.gyro : minus.accel)(c % 3) -= h;
    const ImuPreintegration p = preintegrate(samples, plus), m = preintegrate(samples, minus);
    const Eigen::Vector3d dR = (rotation_log(pim.delta_R().transpose() * p.delta_R()) -
                                rotation_log(pim.delta_R().transpose() * m.delta_R())) /
                               (2 * h);
    const Eigen::Vector3d dv = (p.delta_v() - m.delta_v()) / (2 * h), dp = (p.delta_p() - m.delta_p()) / (2 * h);
    if (c < 3) {
      CHECK((dR - pim.dR_dbg().col(c)).norm() < 1e-6 * (1 + dR.norm()));
      CHECK((dv - pim.dv_dbg().col(c)).norm() < 1e-6 * (1 + dv.norm()));
      CHECK((dp - pim.dp_dbg().col(c)).norm() < 1e-6 * (1 + dp.norm()));
    } else {
      CHECK(dR.norm() < 1e-9);  // the rotation does not depend on the accelerometer bias
      CHECK((dv - pim.dv_dba().col(c - 3)).norm() < 1e-6 * (1 + dv.norm()));
      CHECK((dp - pim.dp_dba().col(c - 3)).norm() < 1e-6 * (1 + dp.norm()));
    }
  }
}

TEST_CASE("preintegration error propagation A, B, C against central differences of one sample") {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1, 1);
  const Eigen::Matrix3d dR = rodrigues(Eigen::Vector3d(0.7, -0.3, 1.2));
  const Eigen::Vector3d dv(0.4, -1.0, 0.2), dp(2.0, 0.5, -0.3), w(0.5, -0.8, 0.3), a(1.0, -0.5, 9.6);
  const double dt = 0.01;
  // One sample from the noisy preintegrated values (dR Exp(e_phi), dv + e_v, dp + e_p) with noisy samples
  // (w + eta_g, a + eta_a); the error after it relative to the noise-free step.
  auto step = [&](const Eigen::Matrix3d& R, const Eigen::Vector3d& v, const Eigen::Vector3d& p,
                  const Eigen::Vector3d& ws, const Eigen::Vector3d& as, Eigen::Matrix3d& R2, Eigen::Vector3d& v2,
                  Eigen::Vector3d& p2) {
    p2 = p + v * dt + 0.5 * R * as * dt * dt;
    v2 = v + R * as * dt;
    R2 = R * rodrigues(ws * dt);
  };
  Eigen::Matrix3d R_ref;
  Eigen::Vector3d v_ref, p_ref;
  step(dR, dv, dp, w, a, R_ref, v_ref, p_ref);
  auto error_after = [&](const Eigen::Matrix<double, 15, 1>& e) {
    Eigen::Matrix3d R2;
    Eigen::Vector3d v2, p2;
    step(dR * rodrigues(e.segment<3>(0)), dv + e.segment<3>(3), dp + e.segment<3>(6), w + e.segment<3>(9),
         a + e.segment<3>(12), R2, v2, p2);
    Eigen::Matrix<double, 9, 1> d;
    d << rotation_log(R_ref.transpose() * R2), v2 - v_ref, p2 - p_ref;
    return d;
  };
  ImuPreintegration::Matrix9 A;
  ImuPreintegration::Matrix93 B, C;
  ImuPreintegration::error_propagation(dR, w, a, dt, &A, &B, &C);
  Eigen::Matrix<double, 9, 15> J;
  J << A, B, C;
  const double h = 1e-6;
  for (int c = 0; c < 15; ++c) {
    Eigen::Matrix<double, 15, 1> e = Eigen::Matrix<double, 15, 1>::Zero();
    e(c) = h;
    const Eigen::Matrix<double, 9, 1> num = (error_after(e) - error_after(-e)) / (2 * h);
    CHECK((num - J.col(c)).norm() < 1e-8);
  }
}

TEST_CASE("first-order bias correction against re-integration, and the covariance against Monte Carlo") {
  std::mt19937 rng(11);
  const std::vector<Sample> samples = random_samples(rng, 200);  // about 1 s
  ImuBias b0, b1;
  b1.gyro = Eigen::Vector3d(0.004, -0.003, 0.005);  // a few mrad/s and cm/s^2: a bias estimate's typical step
  b1.accel = Eigen::Vector3d(0.03, -0.02, 0.04);
  const ImuPreintegration lin = preintegrate(samples, b0), exact = preintegrate(samples, b1);
  const double rot_first = rotation_log(lin.corrected_delta_R(b1).transpose() * exact.delta_R()).norm();
  const double rot_none = rotation_log(lin.delta_R().transpose() * exact.delta_R()).norm();
  const double v_first = (lin.corrected_delta_v(b1) - exact.delta_v()).norm();
  const double v_none = (lin.delta_v() - exact.delta_v()).norm();
  const double p_first = (lin.corrected_delta_p(b1) - exact.delta_p()).norm();
  const double p_none = (lin.delta_p() - exact.delta_p()).norm();
  MESSAGE("bias step over ", lin.dt(), " s: rotation error ", rot_none, " -> ", rot_first, " rad, velocity ", v_none,
          " -> ", v_first, " m/s, position ", p_none, " -> ", p_first, " m (uncorrected -> first-order)");
  // The first-order correction leaves a second-order remainder: at least a hundred times below the uncorrected error.
  CHECK(rot_first < 1e-2 * rot_none);
  CHECK(v_first < 1e-2 * v_none);
  CHECK(p_first < 1e-2 * p_none);

  // Covariance: many noisy integrations of the same motion (discrete noise variance density^2 / dt per sample).
  ImuNoise noise;
  noise.gyro_noise_density = 0.01;
  noise.accel_noise_density = 0.1;
  const ImuPreintegration clean = preintegrate(samples, b0, noise);
  const int runs = 3000;
  Eigen::Matrix<double, 9, 9> empirical = Eigen::Matrix<double, 9, 9>::Zero();
  std::normal_distribution<double> n01;
  for (int r = 0; r < runs; ++r) {
    ImuPreintegration noisy(b0, noise);
    for (const Sample& s : samples) {
      const double sg = noise.gyro_noise_density / std::sqrt(s.dt), sa = noise.accel_noise_density / std::sqrt(s.dt);
      noisy.integrate(s.w + sg * Eigen::Vector3d(n01(rng), n01(rng), n01(rng)),
                      s.a + sa * Eigen::Vector3d(n01(rng), n01(rng), n01(rng)), s.dt);
    }
    Eigen::Matrix<double, 9, 1> d;
    d << rotation_log(clean.delta_R().transpose() * noisy.delta_R()), noisy.delta_v() - clean.delta_v(),
        noisy.delta_p() - clean.delta_p();
    empirical += d * d.transpose() / runs;
  }
  for (int i = 0; i < 9; ++i) {
    INFO("diagonal ", i, ": predicted ", clean.covariance()(i, i), " empirical ", empirical(i, i));
    CHECK(std::abs(empirical(i, i) / clean.covariance()(i, i) - 1) < 0.12);  // 3000 runs: 2.6 % standard error
  }
  // Off-diagonal structure (the v-p and phi-v couplings) in the correlation matrices.
  const Eigen::VectorXd sd_p = clean.covariance().diagonal().cwiseSqrt(), sd_e = empirical.diagonal().cwiseSqrt();
  const Eigen::MatrixXd corr_p =
      sd_p.cwiseInverse().asDiagonal() * clean.covariance() * sd_p.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd corr_e = sd_e.cwiseInverse().asDiagonal() * empirical * sd_e.cwiseInverse().asDiagonal();
  CHECK((corr_p - corr_e).cwiseAbs().maxCoeff() < 0.08);
}

TEST_CASE("preintegration refuses a non-positive dt and non-finite samples") {
  ImuPreintegration pim;
  CHECK_THROWS_AS(pim.integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0), std::invalid_argument);
  CHECK_THROWS_AS(pim.integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), NAN), std::invalid_argument);
  CHECK_THROWS_AS(pim.integrate(Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d::Zero(), 0.01), std::invalid_argument);
  CHECK(pim.dt() == 0);
}

TEST_CASE("EuRoC V1_02: preintegrated dR, dv, dp with the true biases against Vicon ground truth") {
  const EurocExcerpt data = EurocExcerpt::load();
  const Eigen::Vector3d g(0, 0, -9.81);
  for (double window : {0.2, 1.0}) {
    std::vector<double> rot_deg, vel, pos, rot_deg_unbiased, vel_unbiased;
    for (size_t i = 0; i < data.truth.size(); i += static_cast<size_t>(window * 40)) {
      const auto& ti = data.truth[i];
      const auto j_it =
          std::lower_bound(data.truth.begin() + static_cast<long>(i), data.truth.end(), ti.t + window - 1e-6,
                           [](const EurocExcerpt::Truth& a, double t) { return a.t < t; });
      if (j_it == data.truth.end() || j_it->t > data.imu.back().t) break;
      const auto& tj = *j_it;
      ImuBias b;
      b.gyro = ti.b_g, b.accel = ti.b_a;
      const ImuPreintegration pim = data.preintegrate(ti.t, tj.t, b);
      const Eigen::Matrix3d Ri = ti.q.toRotationMatrix(), Rj = tj.q.toRotationMatrix();
      const double T = tj.t - ti.t;
      rot_deg.push_back(rotation_log(pim.delta_R().transpose() * Ri.transpose() * Rj).norm() * 180 / M_PI);
      vel.push_back((pim.delta_v() - Ri.transpose() * (tj.v - ti.v - g * T)).norm());
      pos.push_back((pim.delta_p() - Ri.transpose() * (tj.p - ti.p - ti.v * T - 0.5 * g * T * T)).norm());
      // The same window with the biases ignored: the true biases must make it better (a sign or frame error would not).
      const ImuPreintegration raw = data.preintegrate(ti.t, tj.t, ImuBias{});
      rot_deg_unbiased.push_back(rotation_log(raw.delta_R().transpose() * Ri.transpose() * Rj).norm() * 180 / M_PI);
      vel_unbiased.push_back((raw.delta_v() - Ri.transpose() * (tj.v - ti.v - g * T)).norm());
    }
    auto median = [](std::vector<double> x) {
      std::nth_element(x.begin(), x.begin() + static_cast<long>(x.size() / 2), x.end());
      return x[x.size() / 2];
    };
    auto max = [](const std::vector<double>& x) { return *std::max_element(x.begin(), x.end()); };
    MESSAGE("EuRoC V1_02 ", window, " s windows (", rot_deg.size(), "): rotation median ", median(rot_deg), " max ",
            max(rot_deg), " deg; velocity median ", median(vel), " max ", max(vel), " m/s; position median ",
            median(pos), " max ", max(pos), " m; biases ignored: rotation median ", median(rot_deg_unbiased),
            " deg, velocity median ", median(vel_unbiased), " m/s");
    REQUIRE(rot_deg.size() >= static_cast<size_t>(30 / window));
    // Bounds about three times the figures measured (0.2 s: 0.03 deg, 13 mm/s, 1.5 mm; 1 s: 0.08 deg, 46 mm/s, 26 mm,
    // much of it the noise of Vicon's velocity); a wrong sign, frame or gravity gives degrees and metres.
    CHECK(median(rot_deg) < 0.5 * median(rot_deg_unbiased));
    CHECK(median(vel) < median(vel_unbiased));
    if (window < 0.5) {
      CHECK(median(rot_deg) < 0.1);
      CHECK(median(vel) < 0.04);
      CHECK(median(pos) < 0.005);
    } else {
      CHECK(median(rot_deg) < 0.25);
      CHECK(median(vel) < 0.15);
      CHECK(median(pos) < 0.08);
    }
  }
}

TEST_CASE("preintegrated-IMU factor: zero residual on the integrated states, Jacobians against central differences") {
  std::mt19937 rng(13);
  const std::vector<Sample> samples = random_samples(rng, 150);
  ImuBias b0;
  b0.gyro = Eigen::Vector3d(0.01, 0.02, -0.01);
  b0.accel = Eigen::Vector3d(-0.1, 0.05, 0.2);
  const ImuPreintegration pim = preintegrate(samples, b0);
  const Eigen::Vector3d g(0, 0, -9.81);
  NavState i;
  i.R = rodrigues(Eigen::Vector3d(0.3, -0.5, 1.0));
  i.v = Eigen::Vector3d(1, 0.5, -0.2);
  i.p = Eigen::Vector3d(3, -4, 1);
  const NavState j = pim.predict(i, b0, g);
  CHECK(pim.residual(i, j, b0, g).norm() < 1e-9);

  // Away from the solution and from the linearisation point, so that every term of the Jacobians is exercised.
  NavState jj = j;
  jj.R = j.R * rodrigues(Eigen::Vector3d(0.05, -0.02, 0.04));
  jj.v += Eigen::Vector3d(0.1, -0.2, 0.05);
  jj.p += Eigen::Vector3d(-0.3, 0.1, 0.2);
  ImuBias b = b0;
  b.gyro += Eigen::Vector3d(0.003, -0.002, 0.004);
  b.accel += Eigen::Vector3d(0.02, 0.01, -0.03);
  ImuPreintegration::Matrix9x15 Ji;
  ImuPreintegration::Matrix9 Jj;
  pim.residual(i, jj, b, g, &Ji, &Jj);
  // The error states: [dp, dv, dth, db_a, db_g] at i, [dp, dv, dth] at j.
  auto perturbed = [&](const Eigen::Matrix<double, 24, 1>& e) {
    NavState a = i, c = jj;
    ImuBias bb = b;
    a.p += e.segment<3>(0), a.v += e.segment<3>(3), a.R = a.R * rodrigues(e.segment<3>(6));
    bb.accel += e.segment<3>(9), bb.gyro += e.segment<3>(12);
    c.p += e.segment<3>(15), c.v += e.segment<3>(18), c.R = c.R * rodrigues(e.segment<3>(21));
    return pim.residual(a, c, bb, g);
  };
  Eigen::Matrix<double, 9, 24> J;
  J << Ji, Jj;
  const double h = 1e-6;
  for (int c = 0; c < 24; ++c) {
    Eigen::Matrix<double, 24, 1> e = Eigen::Matrix<double, 24, 1>::Zero();
    e(c) = h;
    const Eigen::Matrix<double, 9, 1> num = (perturbed(e) - perturbed(-e)) / (2 * h);
    INFO("column ", c);
    CHECK((num - J.col(c)).norm() < 1e-6);
  }
}
