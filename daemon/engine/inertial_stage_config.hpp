#pragma once
// Configuration of the inertial filter stage (inertial_stage.hpp): sensor mountings, IMU noise, which fields of
// each sensor are fused, late measurements, the GNSS datum.  Read from engine.inertial (daemon/config/), documented in
// config/default.yaml.
#include <array>
#include <optional>
#include <string>
#include <vector>

namespace sextant::engine {

/// Where one sensor of a body sits: the transform body -> sensor as ROS's static_transform_publisher gives it
/// (translation in metres, then roll, pitch, yaw in radians composed R = Rz(yaw) Ry(pitch) Rx(roll)).
struct SensorMountingConfig {
  std::string source;  // the body ("" = every body)
  std::string frame;   // imu_t.frame / gnss_t.frame
  std::array<double, 3> xyz{0, 0, 0};
  std::array<double, 3> rpy{0, 0, 0};
};

/// The inertial keyframe smoother beside the filter (inertial_graph_stage.hpp), engine.inertial.graph.
struct InertialGraphConfig {
  bool enabled = false;
  double keyframe_interval = 0.5;     // s between keyframes (at odometry messages)
  int window = 20;                    // keyframes kept; the oldest is marginalized
  double gnss_kernel_width = 2.7955;  // Huber width on the whitened fix error (sqrt of chi-square(3)'s 95 %)
  double initial_yaw_sigma = 0.5;     // rad, the start's yaw (0 without a unit's orientation) until GNSS observes it
};

/// The heading of a body's frame in East-North-Up from its first GNSS fixes (estimators/inertial/gnss_heading.hpp),
/// engine.inertial.gnss_heading.  While the heading is not known, fixes are not fused: the body dead-reckons in its
/// own frame (placed at the first fix) until its track spans `baseline_m`; then its state is moved into ENU and the
/// fixes are gated and fused from there on.
struct GnssHeadingConfig {
  enum class Align { kAuto, kAlways, kNever };
  /// kAuto: when the body's yaw is not ENU already (the IMU's yaw is not fused, or the unit has none); kAlways; kNever
  /// (the start's yaw is trusted as ENU: fixes are fused from the first).
  Align align = Align::kAuto;
  double baseline_m = 20;            // m of dead-reckoned track before the heading is estimated
  double min_inlier_fraction = 0.6;  // of the fixes so far the heading must explain (multipath: wait for more)
  /// The filter (whose gate refuses fixes, unlike the smoother's robust kernel): after this many consecutive gated
  /// fixes the estimate has left them (its heading drifted, or the fixes jumped) and would never take one again, so the
  /// heading and position are estimated anew from the next fixes; 0: never.  Not with align kNever.
  int reacquire_after = 10;
};

struct InertialConfig {
  bool enabled = false;  // the stage runs only for users who say they have an IMU
  std::vector<SensorMountingConfig> mountings;
  /// IMU white noise (densities) and bias random walks, SI units per sqrt(s).
  double gyro_noise_density = 3.6e-3, accel_noise_density = 1.8e-2;
  double gyro_bias_random_walk = 1e-4, accel_bias_random_walk = 1e-3;
  /// Which components are fused (robot_localization's per-field selection): the IMU's orientation [roll, pitch, yaw]
  /// (yaw only from units whose orientation has a yaw), the wheel odometry's body velocity [vx, vy, vz], GNSS
  /// position [E, N, U] and velocity.
  std::array<bool, 3> imu_orientation{true, true, true};
  std::array<bool, 3> odometry_velocity{true, true, true};
  std::array<bool, 3> gnss_position{true, true, true};
  std::array<bool, 3> gnss_velocity{false, false, false};
  /// Variances used where a message states none (a zero covariance): orientation rad^2, velocity (m/s)^2.
  double default_orientation_variance = 1e-3, default_velocity_variance = 1e-2, default_gnss_variance = 4.0;
  /// Chi-square gate (Mahalanobis squared) of GNSS position fixes; 0: none.  A multipath outlier is refused, counted.
  double gnss_gate = 16.27;  // 3 degrees of freedom, 0.999
  /// Late measurements: how far back (seconds of data time) a measurement is inserted where it belongs.
  double history_s = 1.0;
  /// FUSED_POSE "inertial" per body at most this often (data time; the IMU may run at 1 kHz).
  double publish_rate_hz = 50;
  /// The ENU datum [latitude deg, longitude deg, altitude m]; empty: the first fix of each body.
  std::vector<double> datum;
  /// Initial standard deviations of the biases.
  double initial_sigma_gyro_bias = 0.01, initial_sigma_accel_bias = 0.1;
  GnssHeadingConfig gnss_heading;
  InertialGraphConfig graph;
};

}  // namespace sextant::engine
