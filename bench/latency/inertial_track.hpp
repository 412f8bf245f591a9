#pragma once
// The sensors of a robot driving OdometryTrack's path, for the latency benchmark's inertial mode: at every step an
// IMU sample (frame "imu", mounted at the body origin), every odometry_every steps the wheel odometry with its twist,
// every gnss_every steps a GNSS fix (frame "gps", at the body origin) in a tangent plane at `datum`.
//   angular velocity   [0, 0, w(t_k)]                (rad/s; the path is planar)
//   specific force     [0, v w(t_k), g]              (m/s^2: the turn's centripetal acceleration, and gravity's
//                                                     reaction; the speed v is constant)
//   twist              linear [v, 0, 0], angular [0, 0, w(t_k)]
//   fix                the pose's position in ENU at the datum, 0.5 m sigma (no noise: the benchmark times, it
//                      does not estimate)
#include "bench/latency/odometry_track.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"

#include <optional>

namespace sextant::bench {

struct InertialSensors {
  engine::ImuSample imu;
  engine::Odometry odometry;  // the step's odometry (published every odometry_every steps)
  bool publish_odometry = false;
  std::optional<engine::GnssFix> fix;  // every gnss_every steps
};

class InertialTrack {
 public:
  InertialTrack(const OdometryTrackOptions& o, int64_t odometry_every, int64_t gnss_every,
                const geodesy::Geodetic& datum = {47.0, 8.0, 500.0})
      : track_(o), odometry_every_(odometry_every), gnss_every_(gnss_every), plane_(datum) {}

  InertialSensors next() {
    InertialSensors s;
    const double w = track_.turn_rate(k_), v = track_.options().speed;
    s.odometry = track_.next();
    engine::Odometry::Twist twist;
    twist.linear = {v, 0, 0};
    twist.angular = {0, 0, w};
    twist.covariance = engine::Matrix6::Identity() * 1e-4;
    s.odometry.twist = twist;
    s.publish_odometry = k_ % odometry_every_ == 0;
    s.imu.utime = s.odometry.utime;
    s.imu.source = s.odometry.source;
    s.imu.frame = "imu";
    s.imu.angular_velocity = Eigen::Vector3d(0, 0, w);
    s.imu.angular_velocity_covariance = Eigen::Matrix3d::Identity() * 1e-6;
    s.imu.linear_acceleration = Eigen::Vector3d(0, v * w, 9.80665);
    s.imu.linear_acceleration_covariance = Eigen::Matrix3d::Identity() * 1e-4;
    if (k_ % gnss_every_ == 0) {
      engine::GnssFix f;
      f.utime = s.odometry.utime;
      f.source = s.odometry.source;
      f.frame = "gps";
      const geodesy::Geodetic g = plane_.to_geodetic(s.odometry.pose.position);
      f.latitude = g.latitude, f.longitude = g.longitude, f.altitude = g.altitude;
      f.position_covariance = Eigen::Matrix3d::Identity() * 0.25;
      s.fix = f;
    }
    ++k_;
    return s;
  }

 private:
  OdometryTrack track_;
  int64_t odometry_every_, gnss_every_;
  geodesy::LocalTangentPlane plane_;
  int64_t k_ = 0;
};

}  // namespace sextant::bench
