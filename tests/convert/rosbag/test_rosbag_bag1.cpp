// robot_localization's EKF test on its bag 1, with sextant's inertial error-state filter as a plain library call:
// the bag converted by convert_rosbag (frames base_link and imu_link both the body "husky"), fused as that test fuses
// it (wheel odometry vx, vy, vz; the IMU's orientation; the IMU's rates and accelerations, here the filter's
// prediction rather than measurements), and the final position in the odometry frame against the test's
// (-40.0454, -76.9988, -2.6974) m within its 1.0452 m.
//
// The IMU's mounting base_link -> imu_link: x 0, y -0.3, z 0.52 m, roll pi/2, pitch 0, yaw -pi/2, i.e. the test's
// static_transform_publisher arguments "0 -0.3 0.52 -1.5708 0 1.5708" in that tool's order (x y z yaw pitch roll).
// The data agree (checked here): the IMU's y axis reads +g at rest and its y rate follows the wheel odometry's yaw
// rate, so imu y is body z (up).  Reading the arguments as roll -pi/2, yaw pi/2 turns the body over about x; for
// this test it gives the same track (forward stays forward).
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/inertial/error_state_ekf.hpp"
#include "convert/rosbag/rosbag_converter.hpp"

#include <doctest/doctest.h>

#include <sextant/imu_t.hpp>
#include <sextant/odometry_t.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

using namespace sextant;
using namespace sextant::inertial;

namespace {

Eigen::Matrix3d matrix3(const double (&a)[9]) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a);
}

struct Run {
  ErrorStateEkf filter;
  SensorMounting imu_mount;
  int64_t t0 = -1;
  int imu = 0, odometry = 0, rejected = 0;

  double seconds(int64_t utime) {
    if (t0 < 0) t0 = utime;
    return static_cast<double>(utime - t0) * 1e-6;
  }

  void start(double t, const imu_t& m) {
    EskfState x;
    const Eigen::Quaterniond q_ws(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
    x.q = Eigen::Quaterniond(q_ws.normalized().toRotationMatrix() * imu_mount.rotation.transpose());
    ErrorStateEkf::Matrix15 P = ErrorStateEkf::Matrix15::Zero();
    P.diagonal() << Eigen::Vector3d::Constant(1e-9), Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(1e-3),
        Eigen::Vector3d::Constant(0.1 * 0.1), Eigen::Vector3d::Constant(0.01 * 0.01);
    filter.initialize(t, x, P);
  }

  void on_imu(const imu_t& m) {
    const double t = seconds(m.utime);
    if (!filter.initialized()) start(t, m);
    const BodyImuSample s =
        imu_to_body(imu_mount, Eigen::Vector3d(m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]),
                    Eigen::Vector3d(m.linear_acceleration[0], m.linear_acceleration[1], m.linear_acceleration[2]));
    filter.add_imu(t, s);
    ++imu;
    if (m.has_orientation) {
      const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
      if (!filter.update_orientation(q, matrix3(m.orientation_covariance), imu_mount).accepted) ++rejected;
    }
  }

  void on_odometry(const odometry_t& m) {
    if (!filter.initialized() || !m.has_twist) return;
    filter.propagate_to(seconds(m.utime));  // a message older than the state is applied at the state's time
    Eigen::Matrix3d R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R(i, j) = m.twist_covariance[6 * i + j];
    const Eigen::Vector3d v(m.linear_velocity[0], m.linear_velocity[1], m.linear_velocity[2]);
    if (!filter.update_body_velocity(v, R, SensorMounting{}).accepted) ++rejected;
    ++odometry;
  }
};

}  // namespace

TEST_CASE("robot_localization bag 1: the inertial filter ends within robot_localization's tolerance of its EKF") {
  const std::string bag = std::string(SEXTANT_SHARED_DIR) + "/data/inertial/robot_localization_bag1/test1.bag";
  const std::string log_path = (std::filesystem::temp_directory_path() / "sextant_test_bag1.lcm").string();
  tools::RosbagConversionOptions conv;
  conv.bodies = {{"base_link", "husky"}, {"imu_link", "husky"}};
  const tools::RosbagConversion c = tools::convert_rosbag(bag, log_path, conv);
  REQUIRE(c.written.at("IMU") == 11865);
  REQUIRE(c.written.at("ODOMETRY") == 3952);

  EskfOptions o;
  // The IMU's white noise from the variances its messages state at 30 Hz (4e-4 rad^2/s^2, 9.6e-3 m^2/s^4):
  // density^2 = variance / rate.  Bias random walks: a consumer MEMS unit's.
  o.noise.gyro_noise_density = std::sqrt(4e-4 / 30);
  o.noise.accel_noise_density = std::sqrt(9.6e-3 / 30);
  o.noise.gyro_bias_random_walk = 1e-4;
  o.noise.accel_bias_random_walk = 1e-3;
  Run run{ErrorStateEkf(o), SensorMounting::from_xyz_rpy({0, -0.3, 0.52}, M_PI / 2, 0, -M_PI / 2)};
  double gravity_on_y = 0;
  int at_rest = 0;
  runtime::LogReader log(log_path);
  while (auto rec = log.next()) {
    if (rec->channel == "IMU") {
      imu_t m;
      REQUIRE(runtime::decode_message(rec->data, m));
      if (run.imu < 30) gravity_on_y += m.linear_acceleration[1], ++at_rest;  // the first second: standing still
      run.on_imu(m);
    } else if (rec->channel == "ODOMETRY") {
      odometry_t m;
      REQUIRE(runtime::decode_message(rec->data, m));
      run.on_odometry(m);
    }
  }
  std::filesystem::remove(log_path);
  CHECK(gravity_on_y / at_rest > 9.5);  // the mounting: imu y is up
  const Eigen::Vector3d p = run.filter.state().p, ref(-40.0454, -76.9988, -2.6974);
  MESSAGE("bag 1: final position (", p.x(), ", ", p.y(), ", ", p.z(), ") m, ", (p - ref).norm(),
          " m from robot_localization's EKF (tolerance 1.0452 m); gyro bias ", run.filter.state().b_g.transpose(),
          " rad/s, accel bias ", run.filter.state().b_a.transpose(), " m/s^2");
  CHECK(run.rejected == 0);
  CHECK((p - ref).norm() <= 1.0452);
}
