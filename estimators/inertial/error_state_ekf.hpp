#pragma once
// An error-state Kalman filter for a body carrying an IMU (Sola, "Quaternion kinematics for the error-state Kalman
// filter", arXiv:1711.02508, section 5; equation numbers are that note's), with updates from wheel odometry, the IMU's
// own orientation and GNSS, selected per field like robot_localization's sensor configs.
//
// Frames: the world frame is z-up (East-North-Up when GNSS is fused, see geodesy/local_tangent_plane.hpp); gravity is
// part of the model, g = [0, 0, -9.80665] m/s^2 by default, so IMU samples keep it (specific force, as an IMU
// measures).  The body frame is the robot's (base_link); IMU samples are moved into it first
// (sensor_mounting.hpp: imu_to_body), so the biases are in body axes.
//
// Nominal state x = (p, v, q, b_a, b_g): body position and velocity in the world frame (m, m/s), body-to-world
// rotation q, accelerometer and gyroscope biases (m/s^2, rad/s).  Error state (15) dx = [dp, dv, dth, db_a, db_g]
// (translation first, like every sextant covariance), with the rotation error local, on the right:
// q_true = q (x) Exp(dth) (section 5.3.3 "local angular error"), the convention of estimators/lie.
//
// Prediction with an IMU sample (w_m, a_m) held for dt (eq. 260, with the exact rotation increment):
//   a = q (a_m - b_a) + g,   p += v dt + a dt^2 / 2,   v += a dt,   q <- q (x) Exp((w_m - b_g) dt)
// and the error-state transition F (eq. 269-270, keeping the dt^2 terms of p and the right Jacobian of the rotation
// so that F is the exact Jacobian of this discrete step, which the tests check numerically):
//   dp' = dp + dv dt - R [a_m - b_a]x dth dt^2/2 - R db_a dt^2/2
//   dv' = dv - R [a_m - b_a]x dth dt - R db_a dt
//   dth' = Exp(-(w_m - b_g) dt) dth - Jr((w_m - b_g) dt) db_g dt
// P <- F P F^T + Q with Q = diag(0, sa^2 dt, sg^2 dt, sba^2 dt, sbg^2 dt) (eq. 271, from the noise densities).
//
// Updates z = h(x) + v: the innovation r = z - h(x_nominal) and H = dh/d(dx) at dx = 0 go through the shared Joseph-form
// update (filter/kalman_update.hpp); the estimated error is injected (x <- x (+) dx, eq. 283) and the covariance reset
// with G = diag(I, I, I - [dth/2]x, I, I) (eq. 287).  Measurements are applied at the filter's current time: call
// `propagate_to(t)` first to bring the state to the measurement's time.
// Measurement models (each a 3-vector with a mask selecting the fused components):
//  - wheel-odometry velocity at a sensor mounted at (R_bs, t_bs), in the sensor frame:
//      h = R_bs^T (R^T v + w x t_bs), w = w_m - b_g the latest bias-corrected body rate
//  - orientation [roll, pitch, yaw] (Z-Y-X Euler angles of the body, R = Rz(yaw) Ry(pitch) Rx(roll)) from an IMU's
//    own orientation estimate: yaw-free units fuse roll and pitch only; the innovation is wrapped to (-pi, pi];
//    singular at pitch = +-90 degrees (as robot_localization's state is)
//  - GNSS antenna position at lever arm t: h = p + R t;   GNSS antenna velocity: h = v + R (w x t)
#include "estimators/filter/kalman_update.hpp"
#include "estimators/inertial/imu_preintegration.hpp"
#include "estimators/inertial/sensor_mounting.hpp"

#include <Eigen/Geometry>

#include <array>

namespace sextant::inertial {

struct EskfState {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d b_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b_g = Eigen::Vector3d::Zero();
};

struct EskfOptions {
  ImuNoise noise;  // densities of the IMU (white noise and bias random walks)
  Eigen::Vector3d gravity{0, 0, -9.80665};
  double max_dt = 0.5;  // a longer gap between the state and an IMU sample is refused (a jump in time), seconds
};

/// What an IMU sample did to the filter.
enum class ImuResult {
  propagated,       // the state moved to the sample's time with the previous sample held
  started,          // the first sample: held, nothing integrated yet
  gap,              // more than max_dt after the state: the state's time jumps to the sample, which is held; the gap's
                    // motion is not integrated (the caller counts it; the state is kept as it was)
  out_of_order,     // before the state's time: dropped
  non_finite,       // a NaN or infinity in the sample: dropped
  not_initialized,  // before initialize(): dropped
};
const char* imu_result_name(ImuResult r);

/// Which of a 3-vector measurement's components are fused (robot_localization's per-field config).
using FieldMask = std::array<bool, 3>;
inline constexpr FieldMask kAllFields{true, true, true};

class ErrorStateEkf {
 public:
  static constexpr int kDim = 15;
  using Matrix15 = Eigen::Matrix<double, kDim, kDim>;
  using Vector15 = Eigen::Matrix<double, kDim, 1>;
  using Matrix3x15 = Eigen::Matrix<double, 3, kDim>;
  enum Block { kP = 0, kV = 3, kTheta = 6, kBa = 9, kBg = 12 };  // offsets in the error state

  explicit ErrorStateEkf(const EskfOptions& options = {}) : options_(options) {}

  /// Starts at time t (seconds) with state x and error covariance P.
  void initialize(double t, const EskfState& x, const Matrix15& P);
  bool initialized() const { return initialized_; }

  /// An IMU sample in the body frame at time t (seconds): the state is propagated from its time to t with the
  /// previous sample held (zero-order hold), then this sample is held.
  ImuResult add_imu(double t, const BodyImuSample& sample);
  /// Propagates to time t with the held sample, so that a measurement taken at t applies there.  False (nothing
  /// changes) when t is before the state's time, no sample is held yet, or t is more than max_dt ahead.
  bool propagate_to(double t);

  /// Wheel-odometry velocity [vx, vy, vz] (m/s) measured in the frame of a sensor mounted at `m`, covariance R.
  filter::UpdateResult update_body_velocity(const Eigen::Vector3d& z, const Eigen::Matrix3d& R, const SensorMounting& m,
                                            const FieldMask& fields = kAllFields, double gate = 0);
  /// An IMU's orientation estimate q_ws (sensor to world) of a unit mounted with rotation R_bs: the body's
  /// orientation R_ws R_bs^T as roll, pitch, yaw with covariance R (rad^2, over [roll, pitch, yaw]).
  /// Yaw-free units: fields {true, true, false}.
  filter::UpdateResult update_orientation(const Eigen::Quaterniond& q_ws, const Eigen::Matrix3d& R,
                                          const SensorMounting& m, const FieldMask& fields = kAllFields,
                                          double gate = 0);
  /// GNSS antenna position in the world (ENU) frame, m, covariance R; the antenna at lever arm `lever` (body frame).
  filter::UpdateResult update_gnss_position(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                            const Eigen::Vector3d& lever, const FieldMask& fields = kAllFields,
                                            double gate = 0);
  /// GNSS antenna velocity in the world (ENU) frame, m/s.
  filter::UpdateResult update_gnss_velocity(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                            const Eigen::Vector3d& lever, const FieldMask& fields = kAllFields,
                                            double gate = 0);

  double time() const { return t_; }
  const EskfState& state() const { return x_; }
  const Matrix15& covariance() const { return P_; }
  /// The body's angular velocity from the held sample, bias-corrected (rad/s, body frame).
  Eigen::Vector3d angular_velocity() const { return held_.gyro - x_.b_g; }

  // The models, public for the tests (Jacobians against numerical differentiation) and for other estimators.
  /// One nominal step with the sample (w_m, a_m) held for dt; F = d(dx')/d(dx) when asked.
  static EskfState step(const EskfState& x, const BodyImuSample& s, double dt, const Eigen::Vector3d& gravity,
                        Matrix15* F = nullptr);
  /// x (+) dx (eq. 283).
  static EskfState inject(const EskfState& x, const Vector15& dx);
  /// x_b (-) x_a, the error state taking x_a to x_b (the inverse of inject).
  static Vector15 difference(const EskfState& x_b, const EskfState& x_a);
  static Eigen::Vector3d body_velocity_model(const EskfState& x, const Eigen::Vector3d& gyro, const SensorMounting& m,
                                             Matrix3x15* H);
  static Eigen::Vector3d euler_model(const EskfState& x, Matrix3x15* H);
  static Eigen::Vector3d gnss_position_model(const EskfState& x, const Eigen::Vector3d& lever, Matrix3x15* H);
  static Eigen::Vector3d gnss_velocity_model(const EskfState& x, const Eigen::Vector3d& gyro,
                                             const Eigen::Vector3d& lever, Matrix3x15* H);
  /// Z-Y-X Euler angles [roll, pitch, yaw] of a rotation matrix.
  static Eigen::Vector3d roll_pitch_yaw(const Eigen::Matrix3d& R);

 private:
  filter::UpdateResult fuse(const Eigen::Vector3d& innovation, const Matrix3x15& H, const Eigen::Matrix3d& R,
                            const FieldMask& fields, double gate);
  void propagate(double dt);

  EskfOptions options_;
  bool initialized_ = false;
  bool has_sample_ = false;
  double t_ = 0;
  EskfState x_;
  Matrix15 P_ = Matrix15::Identity();
  BodyImuSample held_;
};

}  // namespace sextant::inertial
