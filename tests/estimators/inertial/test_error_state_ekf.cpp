// The inertial error-state Kalman filter: the transition and measurement Jacobians against central differences on
// the error state; gravity in the model; per-field selection; refusals; and a simulated 3-D run (IMU with biases and
// noise, GNSS with a lever arm, wheel velocity, yaw-free orientation) that must converge with a consistent covariance.
#include "estimators/inertial/error_state_ekf.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <random>

using namespace sextant::inertial;
using Vector15 = ErrorStateEkf::Vector15;
using Matrix15 = ErrorStateEkf::Matrix15;
using Matrix3x15 = ErrorStateEkf::Matrix3x15;

namespace {

Eigen::Vector3d random_vector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1, 1);
  return scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
}

EskfState random_state(std::mt19937& rng) {
  EskfState x;
  x.p = random_vector(rng, 10);
  x.v = random_vector(rng, 2);
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, random_vector(rng, 1).normalized()) *
                           Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ()));
  x.b_a = random_vector(rng, 0.1);
  x.b_g = random_vector(rng, 0.01);
  return x;
}

Vector15 unit(int c, double h) {
  Vector15 e = Vector15::Zero();
  e(c) = h;
  return e;
}

// Central differences of a measurement model over the error state; `wrap` for angles.
template <class Model>
Matrix3x15 numerical_H(const EskfState& x, Model h_of, bool wrap = false) {
  Matrix3x15 H;
  const double h = 1e-6;
  for (int c = 0; c < 15; ++c) {
    Eigen::Vector3d d = h_of(ErrorStateEkf::inject(x, unit(c, h))) - h_of(ErrorStateEkf::inject(x, unit(c, -h)));
    if (wrap)
      for (int i = 0; i < 3; ++i) d(i) = std::remainder(d(i), 2 * M_PI);
    H.col(c) = d / (2 * h);
  }
  return H;
}

}  // namespace

TEST_CASE("ESKF: the transition Jacobian F against central differences of the nominal step") {
  std::mt19937 rng(4);
  const Eigen::Vector3d g(0, 0, -9.80665);
  for (int trial = 0; trial < 10; ++trial) {
    const EskfState x = random_state(rng);
    BodyImuSample s;
    s.gyro = random_vector(rng, 1.5);
    s.accel = random_vector(rng, 3) + Eigen::Vector3d(0, 0, 9.8);
    const double dt = 0.02;
    Matrix15 F;
    const EskfState y = ErrorStateEkf::step(x, s, dt, g, &F);
    const double h = 1e-6;
    for (int c = 0; c < 15; ++c) {
      const Vector15 num =
          (ErrorStateEkf::difference(ErrorStateEkf::step(ErrorStateEkf::inject(x, unit(c, h)), s, dt, g), y) -
           ErrorStateEkf::difference(ErrorStateEkf::step(ErrorStateEkf::inject(x, unit(c, -h)), s, dt, g), y)) /
          (2 * h);
      INFO("column ", c);
      CHECK((num - F.col(c)).norm() < 1e-7);
    }
  }
}

TEST_CASE("ESKF: measurement Jacobians against central differences, and inject/difference inverse") {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 10; ++trial) {
    const EskfState x = random_state(rng);
    const Eigen::Vector3d gyro = random_vector(rng, 1), lever = random_vector(rng, 0.8);
    SensorMounting m;
    m.rotation = Eigen::AngleAxisd(1.0, random_vector(rng, 1).normalized()).toRotationMatrix();
    m.lever_arm = lever;
    Matrix3x15 H;

    ErrorStateEkf::body_velocity_model(x, gyro, m, &H);
    CHECK((H - numerical_H(x, [&](const EskfState& s) {
             return ErrorStateEkf::body_velocity_model(s, gyro, m, nullptr);
           })).norm() < 1e-7);
    ErrorStateEkf::gnss_position_model(x, lever, &H);
    CHECK((H - numerical_H(x, [&](const EskfState& s) {
             return ErrorStateEkf::gnss_position_model(s, lever, nullptr);
           })).norm() < 1e-7);
    ErrorStateEkf::gnss_velocity_model(x, gyro, lever, &H);
    CHECK((H - numerical_H(x, [&](const EskfState& s) {
             return ErrorStateEkf::gnss_velocity_model(s, gyro, lever, nullptr);
           })).norm() < 1e-7);
    ErrorStateEkf::euler_model(x, &H);
    CHECK((H - numerical_H(
                   x, [&](const EskfState& s) { return ErrorStateEkf::euler_model(s, nullptr); }, true))
              .norm() < 1e-7);

    const Vector15 dx = (Vector15() << random_vector(rng, 1), random_vector(rng, 1), random_vector(rng, 0.5),
                         random_vector(rng, 0.1), random_vector(rng, 0.01))
                            .finished();
    CHECK((ErrorStateEkf::difference(ErrorStateEkf::inject(x, dx), x) - dx).norm() < 1e-12);
  }
}

TEST_CASE("ESKF: gravity is in the model: an IMU at rest reading +g keeps the body still") {
  EskfOptions o;
  ErrorStateEkf f(o);
  EskfState x;
  x.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  f.initialize(0, x, Matrix15::Identity() * 1e-4);
  BodyImuSample s;
  s.accel = x.q.conjugate() * Eigen::Vector3d(0, 0, 9.80665);  // specific force of a tilted IMU at rest
  for (int k = 0; k <= 1000; ++k) REQUIRE(f.add_imu(k * 0.01, s) != ImuResult::non_finite);
  CHECK(f.time() == doctest::Approx(10));
  CHECK(f.state().p.norm() < 1e-9);
  CHECK(f.state().v.norm() < 1e-9);
  // The covariance grew with the noise densities: velocity variance by about sa^2 t.
  CHECK(f.covariance()(3, 3) > 1e-4);
}

TEST_CASE("ESKF: per-field selection, gating and refusals") {
  ErrorStateEkf f;
  CHECK(f.add_imu(0, {}) == ImuResult::not_initialized);
  Matrix15 P = Matrix15::Identity() * 0.01;
  f.initialize(0, EskfState{}, P);
  BodyImuSample s;
  s.accel = Eigen::Vector3d(0, 0, 9.80665);
  CHECK(f.add_imu(0.0, s) == ImuResult::started);
  CHECK(f.add_imu(0.01, s) == ImuResult::propagated);
  CHECK(f.add_imu(0.005, s) == ImuResult::out_of_order);
  BodyImuSample bad = s;
  bad.gyro(1) = NAN;
  CHECK(f.add_imu(0.02, bad) == ImuResult::non_finite);
  CHECK(f.add_imu(2.0, s) == ImuResult::gap);
  CHECK(f.time() == 2.0);
  CHECK_FALSE(f.propagate_to(1.0));
  CHECK_FALSE(f.propagate_to(10.0));

  // Yaw-free orientation: roll and pitch move towards the measurement, yaw is untouched.
  const double yaw_before = ErrorStateEkf::roll_pitch_yaw(f.state().q.toRotationMatrix())(2);
  const Eigen::Quaterniond q_meas(Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()));
  auto r = f.update_orientation(q_meas, Eigen::Matrix3d::Identity() * 1e-4, SensorMounting{}, {true, true, false});
  CHECK(r.accepted);
  const Eigen::Vector3d rpy = ErrorStateEkf::roll_pitch_yaw(f.state().q.toRotationMatrix());
  CHECK(rpy(0) > 0.03);
  CHECK(std::abs(rpy(2) - yaw_before) < 1e-9);

  // Only GNSS east: north and up stay.
  const Eigen::Vector3d p_before = f.state().p;
  r = f.update_gnss_position(Eigen::Vector3d(1, 1, 1), Eigen::Matrix3d::Identity() * 0.01, Eigen::Vector3d::Zero(),
                             {true, false, false});
  CHECK(r.accepted);
  CHECK(f.state().p.x() > p_before.x() + 0.3);
  CHECK(std::abs(f.state().p.y() - p_before.y()) < 1e-9);
  CHECK(std::abs(f.state().p.z() - p_before.z()) < 1e-9);

  r = f.update_gnss_position(Eigen::Vector3d(1, 1, 1), Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(),
                             {false, false, false});
  CHECK(r.reason == sextant::filter::UpdateReason::kNoComponents);
  r = f.update_gnss_position(Eigen::Vector3d(NAN, 1, 1), Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  CHECK(r.reason == sextant::filter::UpdateReason::kNonFinite);
  r = f.update_gnss_position(Eigen::Vector3d(500, 1, 1), Eigen::Matrix3d::Identity() * 0.01, Eigen::Vector3d::Zero(),
                             kAllFields, 11.34);
  CHECK(r.reason == sextant::filter::UpdateReason::kGate);
  r = f.update_orientation(Eigen::Quaterniond(0, 0, 0, 0), Eigen::Matrix3d::Identity(), SensorMounting{});
  CHECK(r.reason == sextant::filter::UpdateReason::kNonFinite);
}

TEST_CASE("sensor mounting: ROS roll-pitch-yaw, the check, and an IMU off the body origin") {
  // robot_localization's bag 1 IMU: base_link -> imu_link at (0, -0.3, 0.52), roll pi/2, yaw -pi/2:
  // R = Rz(-pi/2) Rx(pi/2) maps sensor x to body -y, sensor y to body z (up), sensor z to body -x.
  const SensorMounting m = SensorMounting::from_xyz_rpy({0, -0.3, 0.52}, M_PI / 2, 0, -M_PI / 2);
  CHECK((m.rotation * Eigen::Vector3d::UnitX() + Eigen::Vector3d::UnitY()).norm() < 1e-12);
  CHECK((m.rotation * Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitZ()).norm() < 1e-12);
  CHECK((m.rotation * Eigen::Vector3d::UnitZ() + Eigen::Vector3d::UnitX()).norm() < 1e-12);
  SensorMounting bad;
  bad.rotation(0, 1) = 0.1;
  CHECK_THROWS_AS(bad.check("imu0"), std::invalid_argument);
  bad = SensorMounting{};
  bad.rotation = -Eigen::Matrix3d::Identity();  // a reflection
  CHECK_THROWS_AS(bad.check("imu0"), std::invalid_argument);

  // A body spinning at constant w: the IMU at the lever arm feels the centripetal acceleration on top of f_b.
  const Eigen::Vector3d w_b(0.2, -0.1, 0.8), f_b(0.3, 0.1, 9.8);
  const Eigen::Vector3d f_s = m.rotation.transpose() * (f_b + w_b.cross(w_b.cross(m.lever_arm)));
  const BodyImuSample b = imu_to_body(m, m.rotation.transpose() * w_b, f_s);
  CHECK((b.gyro - w_b).norm() < 1e-12);
  CHECK((b.accel - f_b).norm() < 1e-12);
}

TEST_CASE("ESKF: a simulated 3-D run with biased noisy IMU, GNSS, wheel velocity and yaw-free attitude converges") {
  std::mt19937 rng(17);
  std::normal_distribution<double> n01;
  auto noise3 = [&](double s) { return Eigen::Vector3d(s * n01(rng), s * n01(rng), s * n01(rng)); };
  EskfOptions o;
  o.noise.gyro_noise_density = 2e-3;
  o.noise.accel_noise_density = 2e-2;
  o.noise.gyro_bias_random_walk = 1e-5;
  o.noise.accel_bias_random_walk = 1e-4;
  const double dt = 0.005;  // 200 Hz
  const Eigen::Vector3d b_g(0.01, -0.008, 0.015), b_a(0.08, -0.05, 0.1), lever(0.3, -0.1, 0.8);
  SensorMounting wheel;
  wheel.rotation = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  wheel.lever_arm = Eigen::Vector3d(-0.2, 0, 0.1);

  EskfState truth;
  truth.v = Eigen::Vector3d(1, 0, 0);
  Matrix15 P0 = Matrix15::Zero();
  P0.diagonal() << Eigen::Vector3d::Constant(0.01), Eigen::Vector3d::Constant(0.01), Eigen::Vector3d::Constant(1e-4),
      Eigen::Vector3d::Constant(0.04), Eigen::Vector3d::Constant(4e-4);
  ErrorStateEkf f(o);
  EskfState start = truth;
  start.p += Eigen::Vector3d(0.1, -0.1, 0.05);
  f.initialize(0, start, P0);
  double nees_sum = 0;
  int nees_n = 0;
  for (int k = 0; k <= 60 * 200; ++k) {
    const double t = k * dt;
    // The true motion: body rates and world accelerations as smooth functions of time; the IMU measures them.
    BodyImuSample s;
    s.gyro = Eigen::Vector3d(0.1 * std::sin(0.5 * t), 0.08 * std::cos(0.3 * t), 0.25 * std::sin(0.1 * t));
    const Eigen::Vector3d a_world(-0.3 * std::sin(0.2 * t), 0.3 * std::cos(0.2 * t), 0.05 * std::sin(t));
    s.accel = truth.q.conjugate() * (a_world - o.gravity);
    BodyImuSample measured = s;
    measured.gyro += b_g + noise3(o.noise.gyro_noise_density / std::sqrt(dt));
    measured.accel += b_a + noise3(o.noise.accel_noise_density / std::sqrt(dt));
    REQUIRE(f.add_imu(t, measured) != ImuResult::non_finite);
    if (k % 40 == 0) {  // GNSS at 5 Hz: antenna position and velocity
      const Eigen::Matrix3d R = truth.q.toRotationMatrix();
      f.update_gnss_position(truth.p + R * lever + noise3(0.3), Eigen::Matrix3d::Identity() * 0.09, lever);
      f.update_gnss_velocity(truth.v + R * s.gyro.cross(lever) + noise3(0.05), Eigen::Matrix3d::Identity() * 0.0025,
                             lever);
    }
    if (k % 20 == 10) {  // wheel odometry at 10 Hz, orientation (roll, pitch) at 10 Hz
      const Eigen::Vector3d v_s =
          wheel.rotation.transpose() * (truth.q.conjugate() * truth.v + s.gyro.cross(wheel.lever_arm));
      f.update_body_velocity(v_s + noise3(0.03), Eigen::Matrix3d::Identity() * 9e-4, wheel);
      const Eigen::Quaterniond q_meas = truth.q * Eigen::Quaterniond(Eigen::AngleAxisd(0.01, noise3(1).normalized()));
      f.update_orientation(q_meas, Eigen::Matrix3d::Identity() * 1e-4, SensorMounting{}, {true, true, false});
    }
    if (k > 20 * 200 && k % 200 == 0) {  // NEES after the biases had 20 s to converge
      EskfState tx = truth;
      tx.b_a = b_a, tx.b_g = b_g;
      const Vector15 e = ErrorStateEkf::difference(tx, f.state());
      nees_sum += e.dot(f.covariance().ldlt().solve(e));
      ++nees_n;
    }
    truth = ErrorStateEkf::step(truth, s, dt, o.gravity);
  }
  const EskfState& x = f.state();
  MESSAGE("simulated run, 60 s: position error ", (x.p - truth.p).norm(), " m, gyro bias error ", (x.b_g - b_g).norm(),
          " rad/s, accel bias error ", (x.b_a - b_a).norm(), " m/s^2, mean NEES (15 dof) ", nees_sum / nees_n);
  CHECK((x.p - truth.p).norm() < 0.3);
  CHECK((x.v - truth.v).norm() < 0.05);
  CHECK(Eigen::AngleAxisd(x.q.conjugate() * truth.q).angle() < 0.01);
  CHECK((x.b_g - b_g).norm() < 2e-3);
  CHECK((x.b_a - b_a).norm() < 0.05);
  // Consistency: the mean NEES of 40 correlated samples of a 15-dof error, loosely around its expectation 15.
  CHECK(nees_sum / nees_n < 30);
  CHECK(nees_sum / nees_n > 5);
}
