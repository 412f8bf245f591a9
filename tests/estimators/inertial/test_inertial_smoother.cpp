// InertialSmoother on a robot standing still (the simulated moving runs are in tests/sim): the gyroscope's and the
// vertical accelerometer bias estimated from the odometry saying it does not move, the window bounded by
// marginalization, and bad or late input counted and dropped; options out of range named.
#include "estimators/inertial/inertial_smoother.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

using namespace sextant;
using namespace sextant::inertial;

TEST_CASE("InertialSmoother standing still: biases estimated, position held, window bounded") {
  InertialSmootherOptions o;
  o.window = 10;
  InertialSmoother s(o);
  const Eigen::Vector3d gyro_bias(0.002, -0.003, 0.01), accel_bias(0, 0, 0.1);
  BodyImuSample still;
  still.gyro = gyro_bias;
  still.accel = Eigen::Vector3d(0, 0, 9.80665) + accel_bias;
  s.initialize(0, NavState{}, ImuBias{}, SE3());
  Matrix6d q = Matrix6d::Identity() * 1e-8;
  for (int k = 1; k <= 30 * 200; ++k) {  // 30 s of IMU at 200 Hz, odometry at 50 Hz, GNSS at 5 Hz
    const double t = k / 200.0;
    CHECK(s.add_imu(t, still));
    if (k % 4 == 0) CHECK(s.add_odometry(t, SE3(), q));
    if (k % 40 == 0) CHECK(s.add_gnss(t, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity() * 0.25));
  }
  const KeyframeEstimate e = s.newest();
  MESSAGE("after 30 s: gyro bias ", e.bias.gyro.transpose(), ", accel bias ", e.bias.accel.transpose(), ", position ",
          e.state.p.transpose());
  CHECK((e.bias.gyro - gyro_bias).norm() < 2e-4);
  CHECK(std::abs(e.bias.accel.z() - 0.1) < 0.01);
  CHECK(e.state.p.norm() < 0.05);
  CHECK(s.window().size() == 10);
  CHECK(s.counters().keyframes == 61);  // the first, then one every 0.5 s
  CHECK(s.counters().marginalized == 51);
  CHECK(s.counters().failed_solves == 0);
  CHECK(s.counters().dropped == 0);
  CHECK(s.observability().tilt);
}

TEST_CASE("InertialSmoother: input before initialize, out of order, non-finite or with a bad covariance is dropped") {
  InertialSmoother s(InertialSmootherOptions{});
  BodyImuSample still;
  still.accel = Eigen::Vector3d(0, 0, 9.80665);
  CHECK_FALSE(s.add_imu(0, still));
  s.initialize(1, NavState{}, ImuBias{}, SE3());
  CHECK(s.add_imu(1.1, still));
  CHECK_FALSE(s.add_imu(1.05, still));  // before the last sample
  BodyImuSample bad = still;
  bad.gyro.x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(s.add_imu(1.2, bad));
  CHECK_FALSE(s.add_gnss(1.2, Eigen::Vector3d::Zero(), -Eigen::Matrix3d::Identity()));
  CHECK_FALSE(s.add_odometry(1.0, SE3(), Matrix6d::Identity()));  // before the IMU's time
  CHECK(s.counters().dropped == 5);
  CHECK(s.counters().imu == 1);
}

TEST_CASE("InertialSmoother options out of range are named") {
  auto message = [](InertialSmootherOptions o) {
    try {
      check_options(o);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  InertialSmootherOptions o;
  CHECK(message(o).empty());
  o.window = 1;
  CHECK(message(o).find("window") != std::string::npos);
  o = {};
  o.keyframe_interval = 0;
  CHECK(message(o).find("keyframe_interval") != std::string::npos);
  o = {};
  o.noise.accel_bias_random_walk = -1;
  CHECK(message(o).find("accel_bias_random_walk") != std::string::npos);
  o = {};
  o.initial_yaw_sigma = std::numeric_limits<double>::infinity();
  CHECK(message(o).find("initial_yaw_sigma") != std::string::npos);
  CHECK_THROWS_AS(InertialSmoother{o}, std::invalid_argument);
}

TEST_CASE("InertialSmoother: a keyframe whose IMU link cannot be built restarts the smoother, which goes on") {
  // One sample of absurd but finite rates makes the preintegrated covariance indefinite, so the next keyframe's IMU
  // factor refuses it.  The smoother must not stay stuck with that preintegration (every later keyframe refused),
  // nor number its keyframes with a gap (later links referring to variables past the window).
  InertialSmootherOptions o;
  o.window = 6;
  o.use_odometry = false;
  InertialSmoother s(o);
  BodyImuSample still, wild;
  still.accel = Eigen::Vector3d(0, 0, 9.80665);
  wild.gyro = Eigen::Vector3d::Constant(1e300);
  wild.accel = Eigen::Vector3d::Constant(-1e308);
  s.initialize(0, NavState{}, ImuBias{});
  for (int k = 1; k <= 10 * 200; ++k) CHECK_NOTHROW(s.add_imu(k / 200.0, k == 600 ? wild : still));
  CHECK(s.counters().restarts == 1);
  CHECK(s.counters().keyframes >= 20);  // one every 0.5 s over 10 s, the refused one not among them
  CHECK(s.window().size() == 6);
  CHECK(s.newest().t == doctest::Approx(10.0));
  CHECK(s.counters().failed_solves == 0);
  CHECK(s.newest().state.p.allFinite());
  CHECK(std::isfinite(s.newest_pose_covariance().trace()));
}
