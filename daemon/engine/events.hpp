#pragma once
// Typed input events of the engine: what the bus (or a log) delivers, already decoded and validated.
// Plain C++ and Eigen only; the daemon's codec turns LCM messages into these (daemon/runtime/codec.hpp).
//
// Conventions (as in lcmtypes/sextant/*.lcm): times are utime, int64 microseconds; poses are a position in metres and a unit
// quaternion (Eigen stores it as x,y,z,w but its constructor takes w,x,y,z); tangent vectors and covariances are
// ordered translation first, then rotation, with the perturbation on the right (T = T_hat * exp(xi)).
#include "daemon/engine/fleet_events.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <type_traits>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace sextant::engine {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// Body pose in one odometry source's own frame (odometry_t).
struct Odometry {
  int64_t utime = 0;
  std::string source;
  bool planar = false;
  Pose pose;
  Matrix6 covariance = Matrix6::Zero();
  /// Covariance of the motion since this source's previous message, in the previous body frame.
  std::optional<Matrix6> increment_covariance;
  struct Twist {
    Eigen::Vector3d linear = Eigen::Vector3d::Zero();   // m/s, body frame
    Eigen::Vector3d angular = Eigen::Vector3d::Zero();  // rad/s, body frame
    Matrix6 covariance = Matrix6::Zero();
  };
  std::optional<Twist> twist;
};

struct LandmarkObservation {
  int64_t id = -1;                                       // -1: unknown, to be associated
  double range = 0, azimuth = 0, elevation = 0;          // m, rad, rad (sensor frame)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // over [range, azimuth, elevation]
};

/// Landmark sightings of one body at one time (landmarks_t).
struct LandmarkSightings {
  int64_t utime = 0;
  std::string source;
  bool planar = false;
  Pose sensor_in_body;
  std::vector<LandmarkObservation> observations;
};

struct BearingDetection {
  double azimuth = 0, elevation = 0;              // rad, world frame (passive-association paper, eq. 1-2)
  double sigma_azimuth = 0, sigma_elevation = 0;  // rad, > 0
};

/// One scan of one static passive sensor (bearing_scan_t).
struct BearingScan {
  int64_t utime = 0;
  int32_t sensor_id = 0;
  Eigen::Vector3d sensor_position = Eigen::Vector3d::Zero();
  int64_t scan_id = 0;
  std::vector<BearingDetection> detections;
};

/// Relative pose between two times of one body (loop_closure_t).
struct LoopClosure {
  int64_t utime = 0;
  std::string source;     // the body of the "from" pose
  std::string source_to;  // the body of the "to" pose (another body of the fleet); empty: source
  bool planar = false;
  int64_t utime_from = 0, utime_to = 0;
  int64_t keyframe_from = -1, keyframe_to = -1;
  int64_t request_id = -1;
  Pose relative;  // T_from^-1 * T_to
  Matrix6 information = Matrix6::Identity();
  std::string matcher;
  double score = 0;
};

/// One sample of an IMU mounted on a body (imu_t), in the IMU's own frame (`frame` selects its mounting).  A group
/// the message did not carry is empty.  Covariances are 3x3; a zero matrix means "not stated".
struct ImuSample {
  int64_t utime = 0;
  std::string source;
  std::string frame;
  std::optional<Eigen::Vector3d> angular_velocity;  // rad/s, sensor frame
  Eigen::Matrix3d angular_velocity_covariance = Eigen::Matrix3d::Zero();
  std::optional<Eigen::Vector3d> linear_acceleration;  // specific force, m/s^2, sensor frame, gravity not removed
  Eigen::Matrix3d linear_acceleration_covariance = Eigen::Matrix3d::Zero();
  std::optional<Eigen::Quaterniond> orientation;  // sensor to world (ENU when orientation_has_yaw)
  bool orientation_has_yaw = false;
  Eigen::Matrix3d orientation_covariance = Eigen::Matrix3d::Zero();  // rad^2, [roll pitch yaw]
};

/// One fix of a GNSS receiver whose antenna is on a body (gnss_t).  Only fixes (status >= 0) become events.
struct GnssFix {
  int64_t utime = 0;
  std::string source;
  std::string frame;
  int status = 0;                                                 // gnss_t.STATUS_*
  double latitude = 0, longitude = 0, altitude = 0;               // degrees, degrees, metres above the WGS84 ellipsoid
  Eigen::Matrix3d position_covariance = Eigen::Matrix3d::Zero();  // East-North-Up, m^2
  std::optional<Eigen::Vector3d> velocity;                        // East-North-Up, m/s
  Eigen::Matrix3d velocity_covariance = Eigen::Matrix3d::Zero();
};

/// FleetContributions and FleetControl (fleet_events.hpp): what the other daemons of a fleet send on FLEET and
/// FLEET_CONTROL, for the graph stage.
using Event = std::variant<Odometry, LandmarkSightings, BearingScan, LoopClosure, ImuSample, GnssFix,
                           FleetContributions, FleetControl>;

/// The utime every event carries.
inline int64_t event_utime(const Event& e) {
  return std::visit([](const auto& x) { return x.utime; }, e);
}

/// Whom an event is about: the source (body) of odometry, sightings and loop closures; "sensor N" for a bearing scan;
/// the sending daemon of a fleet message.
inline std::string event_source(const Event& e) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, BearingScan>)
          return "sensor " + std::to_string(x.sensor_id);
        else if constexpr (std::is_same_v<T, FleetContributions> || std::is_same_v<T, FleetControl>)
          return x.sender;
        else
          return x.source;
      },
      e);
}

}  // namespace sextant::engine
