// The simulated IMU and GNSS: a noise-free IMU dead-reckons the truth through the error-state filter; the lever arm
// and mounting terms are the ones imu_to_body undoes; bias random walk, GNSS noise, outages and multipath outliers
// have the statistics asked for; a seed gives the same readings.
#include "sim/inertial_sensor_sim.hpp"

#include "estimators/inertial/error_state_ekf.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace sextant;
using namespace sextant::tools;

namespace {

// A body driving a circle of 20 m radius at 2 m/s over hills (slope dz/ds = 0.225 cos 3a), pitching with the slope
// and rolling a little.
Eigen::Isometry3d circuit(double t) {
  const double a = 0.1 * t;
  const Eigen::Vector3d p(20 * std::cos(a), 20 * std::sin(a), 1.5 * std::sin(3 * a));
  const double yaw = a + M_PI / 2, pitch = -std::atan(0.225 * std::cos(3 * a)), roll = 0.05 * std::sin(t);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = p;
  return T;
}

SimulatedImuOptions noise_free_imu() {
  SimulatedImuOptions o;
  o.noise.gyro_noise_density = o.noise.accel_noise_density = 0;
  o.noise.gyro_bias_random_walk = o.noise.accel_bias_random_walk = 0;
  o.initial_gyro_bias_sigma = o.initial_accel_bias_sigma = 0;
  return o;
}

// Dead reckoning over 20 s from the true initial state with noise-free samples at `rate_hz`, each held over its
// interval (taken at the interval's middle), through the error-state filter's nominal integration: the position error.
double dead_reckoning_error(double rate_hz) {
  SimulatedImuOptions o = noise_free_imu();
  o.rate_hz = rate_hz;
  InertialSensorSimulator sim(circuit, o, SimulatedGnssOptions{}, 1);
  const TrueMotion m0 = InertialSensorSimulator::true_motion(circuit, 0, o.gravity);
  inertial::EskfState x;
  x.p = circuit(0).translation();
  x.q = Eigen::Quaterniond(circuit(0).linear());
  x.v = m0.velocity;
  inertial::ErrorStateEkf f;
  f.initialize(0, x, inertial::ErrorStateEkf::Matrix15::Identity() * 1e-6);
  const double dt = 1 / rate_hz;
  for (int k = 0; k <= static_cast<int>(20 * rate_hz); ++k) {
    const ImuReading mid = sim.imu(k * dt + dt / 2);
    f.add_imu(k * dt, inertial::BodyImuSample{mid.gyro, mid.accel});
  }
  return (f.state().p - circuit(20).translation()).norm();
}

}  // namespace

TEST_CASE("simulated IMU: noise-free samples dead-reckon the truth, and imu_to_body undoes the mounting") {
  SimulatedImuOptions o = noise_free_imu();
  o.mounting = inertial::SensorMounting::from_xyz_rpy({0.3, -0.2, 0.5}, 0.3, -0.2, 1.0);
  InertialSensorSimulator sim(circuit, o, SimulatedGnssOptions{}, 1);
  double worst = 0;
  for (int k = 0; k <= 2000; ++k) {
    const double t = k * 0.005;
    const ImuReading r = sim.imu(t);
    const inertial::BodyImuSample b = inertial::imu_to_body(o.mounting, r.gyro, r.accel);
    const TrueMotion m = InertialSensorSimulator::true_motion(circuit, t, o.gravity);
    // imu_to_body leaves the angular-acceleration term alpha x t in (sensor_mounting.hpp).
    worst = std::max({worst, (b.gyro - m.angular_velocity).norm(),
                      (b.accel - m.specific_force - m.angular_acceleration.cross(o.mounting.lever_arm)).norm()});
  }
  CHECK(worst < 1e-9);
  // The samples integrate to the truth: the error is the integrator's first-order one (the rotation within a step
  // is not applied to that step's specific force, Sola eq. 260), shrinking in proportion to the step; an
  // inconsistent sample (sign, frame, gravity) would leave an error that does not shrink.
  const double e200 = dead_reckoning_error(200), e1000 = dead_reckoning_error(1000);
  MESSAGE("noise-free IMU, 20 s dead reckoning: ", e200, " m at 200 Hz, ", e1000, " m at 1 kHz");
  CHECK(e1000 < 0.03);
  CHECK(e200 / e1000 > 4);
  CHECK(e200 / e1000 < 6);
}

TEST_CASE("simulated IMU: the biases walk at the rate asked for") {
  SimulatedImuOptions o = noise_free_imu();
  o.rate_hz = 10;
  o.noise.gyro_bias_random_walk = 1e-3;
  o.noise.accel_bias_random_walk = 1e-2;
  double sg = 0, sa = 0;
  const int seeds = 300;
  const double T = 100;
  for (int s = 0; s < seeds; ++s) {
    InertialSensorSimulator sim(circuit, o, SimulatedGnssOptions{}, static_cast<uint64_t>(s + 1));
    ImuReading r;
    for (int k = 0; k <= static_cast<int>(T * o.rate_hz); ++k) r = sim.imu(k / o.rate_hz);
    sg += r.gyro_bias.squaredNorm() / 3, sa += r.accel_bias.squaredNorm() / 3;
  }
  const double expected_g = 1e-3 * std::sqrt(T), expected_a = 1e-2 * std::sqrt(T);
  CHECK(std::sqrt(sg / seeds) == doctest::Approx(expected_g).epsilon(0.1));
  CHECK(std::sqrt(sa / seeds) == doctest::Approx(expected_a).epsilon(0.1));
}

TEST_CASE("simulated GNSS: noise, outages, multipath outliers, the geodetic fix, and determinism") {
  SimulatedGnssOptions g;
  g.lever_arm = Eigen::Vector3d(0.1, 0, 1.2);
  g.outage_period_s = 100;
  g.outage_duration_s = 20;
  g.outlier_probability = 0.05;
  InertialSensorSimulator sim(circuit, SimulatedImuOptions{}, g, 7), again(circuit, SimulatedImuOptions{}, g, 7);
  int fixes = 0, outliers = 0, in_gap = 0;
  double se = 0, su = 0;
  for (int k = 0; k < 5 * 1000; ++k) {
    const double t = k / g.rate_hz;
    const auto r = sim.gnss(t);
    const auto r2 = again.gnss(t);
    REQUIRE(r.has_value() == r2.has_value());
    if (std::fmod(t, 100) >= 80) {
      in_gap += r.has_value();
      continue;
    }
    REQUIRE(r.has_value());
    CHECK(r->enu == r2->enu);
    const Eigen::Isometry3d T = circuit(t);
    CHECK((r->true_enu - (T.translation() + T.linear() * g.lever_arm)).norm() < 1e-12);
    CHECK((sim.plane().to_enu(r->fix) - r->enu).norm() < 1e-6);
    ++fixes;
    if (r->outlier) {
      ++outliers;
      continue;
    }
    se += (r->enu - r->true_enu).x() * (r->enu - r->true_enu).x();
    su += (r->enu - r->true_enu).z() * (r->enu - r->true_enu).z();
  }
  CHECK(in_gap == 0);
  CHECK(fixes == 4000);
  // 5 % of 4000: 200 expected, binomial sd 14.
  CHECK(outliers > 150);
  CHECK(outliers < 250);
  CHECK(std::sqrt(se / (fixes - outliers)) == doctest::Approx(g.horizontal_sigma).epsilon(0.07));
  CHECK(std::sqrt(su / (fixes - outliers)) == doctest::Approx(g.vertical_sigma).epsilon(0.07));
}
