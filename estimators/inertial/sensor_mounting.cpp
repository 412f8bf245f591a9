#include "estimators/inertial/sensor_mounting.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>
#include <string>

namespace sextant::inertial {

SensorMounting SensorMounting::from_xyz_rpy(const Eigen::Vector3d& xyz, double roll, double pitch, double yaw) {
  SensorMounting m;
  m.rotation = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  m.lever_arm = xyz;
  m.check("mounting");
  return m;
}

void SensorMounting::check(const char* what) const {
  if (!rotation.allFinite() || !lever_arm.allFinite())
    throw std::invalid_argument(std::string(what) + ": rotation and lever arm must be finite");
  const double orthogonality = (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthogonality > 1e-6 || std::abs(rotation.determinant() - 1) > 1e-6)
    throw std::invalid_argument(std::string(what) + ": rotation is not a rotation matrix (R^T R - I off by " +
                                std::to_string(orthogonality) + ", det " + std::to_string(rotation.determinant()) +
                                ")");
}

BodyImuSample imu_to_body(const SensorMounting& m, const Eigen::Vector3d& gyro_sensor,
                          const Eigen::Vector3d& accel_sensor) {
  BodyImuSample b;
  b.gyro = m.rotation * gyro_sensor;
  b.accel = m.rotation * accel_sensor - b.gyro.cross(b.gyro.cross(m.lever_arm));
  return b;
}

}  // namespace sextant::inertial
