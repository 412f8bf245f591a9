#pragma once
// A ground robot driving straight on a heading it does not know, for the inertial stages' tests: level IMU samples
// (200 Hz, no orientation), planar wheel odometry with its twist (50 Hz) and GNSS fixes (5 Hz, antenna 1 m above the
// body, 0.5 m noise per horizontal axis, the third fix 29 m off: multipath; from `jump_at_s` on, every fix 15 m
// further east, as when a receiver changes its corrections), in time order.  At rest for 1 s, then
// 1 m/s^2 along the body's x for 2 s, then 2 m/s.  The datum is the first fix (noise-free), so the body's true
// East-North-Up position at time t is (0, 0, -1) + Rz(heading) [s(t), 0, 0].
#include "daemon/engine/events.hpp"
#include "estimators/geodesy/local_tangent_plane.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <random>
#include <vector>

namespace sextant::engine::test {

struct StraightDrive {
  static constexpr int64_t kT0 = 1'700'000'000'000'000;
  double heading;  // rad, counter-clockwise from East
  std::vector<Event> events;

  /// Distance driven (m) and speed (m/s) at t seconds.
  static double distance(double t) { return t < 1 ? 0 : t < 3 ? 0.5 * (t - 1) * (t - 1) : 2 + 2 * (t - 3); }
  static double speed(double t) { return t < 1 ? 0 : t < 3 ? t - 1 : 2; }
  Eigen::Vector3d body_enu(double t) const {
    return Eigen::Vector3d(0, 0, -1) + distance(t) * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0);
  }

  StraightDrive(double heading_rad, double seconds, double jump_at_s = 1e9) : heading(heading_rad) {
    const geodesy::LocalTangentPlane plane({47.0, 8.0, 500.0});
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0, 0.5);
    int fixes = 0;
    for (int k = 0; k <= static_cast<int>(seconds * 200); ++k) {
      const double t = k / 200.0;
      const int64_t utime = kT0 + 5'000 * k;
      ImuSample s;
      s.utime = utime, s.source = "robot", s.frame = "imu";
      s.angular_velocity = Eigen::Vector3d::Zero();
      s.linear_acceleration = Eigen::Vector3d(t >= 1 && t < 3 ? 1.0 : 0.0, 0, 9.80665);
      events.emplace_back(s);
      if (k % 4 == 0) {
        Odometry o;
        o.utime = utime, o.source = "robot", o.planar = true;
        o.pose.position = Eigen::Vector3d(distance(t), 0, 0);
        o.increment_covariance = Matrix6::Identity() * 1e-6;
        o.twist = Odometry::Twist{Eigen::Vector3d(speed(t), 0, 0), Eigen::Vector3d::Zero(), Matrix6::Identity() * 1e-4};
        events.emplace_back(o);
      }
      if (k % 40 == 0) {
        Eigen::Vector3d antenna = body_enu(t) + Eigen::Vector3d(0, 0, 1);
        if (fixes > 0) antenna += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
        if (fixes == 2) antenna += Eigen::Vector3d(25, -15, 0);
        if (t >= jump_at_s) antenna += Eigen::Vector3d(15, 0, 0);
        const geodesy::Geodetic g = plane.to_geodetic(antenna);
        GnssFix f;
        f.utime = utime, f.source = "robot", f.frame = "gps";
        f.latitude = g.latitude, f.longitude = g.longitude, f.altitude = g.altitude;
        f.position_covariance = Eigen::Matrix3d::Identity() * 0.25;
        events.emplace_back(f);
        ++fixes;
      }
    }
  }
};

}  // namespace sextant::engine::test
