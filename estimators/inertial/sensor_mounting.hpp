#pragma once
// Where a sensor sits on a body: its rotation and lever arm (configuration, checked when it is read).
//
// Frames: R_bs rotates vectors from the sensor frame into the body frame, and t_bs is the sensor's origin in the body
// frame (metres), so a point x_s in the sensor frame is x_b = R_bs x_s + t_bs.  It is the static transform
// body -> sensor of ROS's tf (base_link -> imu_link), whose roll, pitch, yaw compose as R = Rz(yaw) Ry(pitch) Rx(roll)
// (fixed axes x, then y, then z).
//
// An IMU off the body origin: the gyroscope measures the body's angular velocity in its own axes, w_s = R_bs^T w_b;
// the accelerometer measures the specific force at its own origin, f_s = R_bs^T (f_b + alpha x t + w x (w x t)),
// with f_b the specific force at the body origin and alpha the angular acceleration.  `imu_to_body` removes the
// centripetal term w x (w x t) with the measured w; alpha x t is left in (it needs a derivative of a noisy w; it
// averages out over a turn and is below the accelerometer noise for lever arms under a metre at ground-robot rates).
#include <Eigen/Core>

namespace sextant::inertial {

struct SensorMounting {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // R_bs, sensor to body
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();     // t_bs, metres in the body frame

  /// From a ROS static transform: translation (x, y, z) metres, roll, pitch, yaw radians (R = Rz Ry Rx).
  static SensorMounting from_xyz_rpy(const Eigen::Vector3d& xyz, double roll, double pitch, double yaw);
  /// std::invalid_argument naming `what` when a value is not finite or the rotation is not orthonormal with
  /// determinant +1 (to 1e-6), e.g. a hand-typed matrix.
  void check(const char* what) const;
};

/// One IMU sample in the body frame: angular velocity (rad/s) and specific force at the body origin (m/s^2).
struct BodyImuSample {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
};

/// The sample of an IMU mounted at `m`, moved to the body origin (w_b = R_bs w_s, f_b = R_bs f_s - w_b x (w_b x t_bs)).
BodyImuSample imu_to_body(const SensorMounting& m, const Eigen::Vector3d& gyro_sensor,
                          const Eigen::Vector3d& accel_sensor);

}  // namespace sextant::inertial
