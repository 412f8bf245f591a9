#pragma once
// Simulated IMU and GNSS on a body whose true pose is a smooth function of time, with the truth of every error.
//
// IMU (the sensor mounted at `mounting` on the body, sampled at rate_hz):
//   w_s = R_bs^T w_b + b_g + n_g,   f_s = R_bs^T (R^T (a - g) + alpha x t + w x (w x t)) + b_a + n_a
// where w_b (body angular velocity), a (world acceleration) and alpha (angular acceleration) come from central
// differences of the true pose over h = 1 ms; n_g, n_a are white with variance density^2 * rate (the discrete form of
// the continuous densities), and the biases start at N(0, initial sigma^2) and walk: b <- b + N(0, rw^2 dt) per sample.
// GNSS (antenna at lever arm t_a, rate_hz): the antenna's true position p + R t_a in the world (East-North-Up at
// `datum`) plus N(0, diag(sh^2, sh^2, sv^2)), as latitude/longitude/altitude through the tangent plane; its velocity
// plus N(0, sv_vel^2 I).  Outages: no fix in [k P + P - D, (k + 1) P) for outage period P and duration D (the last D
// seconds of every period).  Multipath: with probability p_out a fix is moved by an extra N(0, outlier_sigma^2) per
// horizontal axis and flagged in the truth (the message itself does not say so, as a receiver does not).
// Deterministic for a seed.
#include "estimators/geodesy/local_tangent_plane.hpp"
#include "estimators/inertial/imu_preintegration.hpp"
#include "estimators/inertial/sensor_mounting.hpp"

#include <sextant/gnss_t.hpp>
#include <sextant/imu_t.hpp>

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <string>

namespace sextant::tools {

/// The true body pose (body-to-world) at time t, seconds.
using TruthFunction = std::function<Eigen::Isometry3d(double t)>;

struct SimulatedImuOptions {
  double rate_hz = 200;
  inertial::ImuNoise noise;
  double initial_gyro_bias_sigma = 0.005;  // rad/s per axis
  double initial_accel_bias_sigma = 0.05;  // m/s^2 per axis
  inertial::SensorMounting mounting;
  Eigen::Vector3d gravity{0, 0, -9.80665};
};

struct SimulatedGnssOptions {
  double rate_hz = 5;
  double horizontal_sigma = 0.5, vertical_sigma = 1.0;  // m
  double velocity_sigma = 0.05;                         // m/s per axis
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();  // antenna in the body frame, m
  geodesy::Geodetic datum{47.3769, 8.5417, 410};        // the world frame's origin on the ellipsoid
  double outage_period_s = 0, outage_duration_s = 0;    // 0: no outages
  double outlier_probability = 0;
  double outlier_sigma = 10;  // m per horizontal axis
};

/// The body's true motion at t: angular velocity (body frame, rad/s) and specific force at the body origin (m/s^2).
struct TrueMotion {
  Eigen::Vector3d angular_velocity, specific_force, velocity, angular_acceleration;
};

struct ImuReading {
  double t = 0;
  Eigen::Vector3d gyro, accel;            // as the sensor reports them (its frame, biases and noise in)
  Eigen::Vector3d gyro_bias, accel_bias;  // the true biases at t
};

struct GnssReading {
  double t = 0;
  geodesy::Geodetic fix;
  Eigen::Vector3d enu, true_enu;            // measured and true antenna position in the world frame
  Eigen::Vector3d velocity, true_velocity;  // antenna velocity, world frame
  bool outlier = false;
};

class InertialSensorSimulator {
 public:
  InertialSensorSimulator(TruthFunction truth, const SimulatedImuOptions& imu, const SimulatedGnssOptions& gnss,
                          uint64_t seed);

  /// Central differences of the truth at t (h = 1 ms).
  static TrueMotion true_motion(const TruthFunction& truth, double t, const Eigen::Vector3d& gravity);
  /// The IMU's sample at t (call with increasing t: the bias walk advances by the time since the previous call).
  ImuReading imu(double t);
  /// The receiver's fix at t; nullopt during an outage.
  std::optional<GnssReading> gnss(double t);
  bool in_outage(double t) const;

  const geodesy::LocalTangentPlane& plane() const { return plane_; }

  static sextant::imu_t to_message(const ImuReading& r, const SimulatedImuOptions& o, int64_t utime,
                                   const std::string& source, int64_t seq);
  static sextant::gnss_t to_message(const GnssReading& r, const SimulatedGnssOptions& o, int64_t utime,
                                    const std::string& source, int64_t seq);

 private:
  Eigen::Vector3d gauss3(double sx, double sy, double sz);

  TruthFunction truth_;
  SimulatedImuOptions imu_;
  SimulatedGnssOptions gnss_;
  geodesy::LocalTangentPlane plane_;
  std::mt19937_64 rng_;
  Eigen::Vector3d b_g_, b_a_;
  std::optional<double> last_imu_t_;
};

}  // namespace sextant::tools
