#include "daemon/runtime/codec.hpp"

#include "daemon/runtime/codec_fields.hpp"
#include "daemon/runtime/codec_validation.hpp"
#include "daemon/runtime/wire_layout.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <span>
#include <sstream>

namespace sextant::runtime {

using namespace codec_fields;
using namespace codec_validation;

namespace {

using codec_validation::check_finite;  // the array form, beside this one

double check_finite(double v, const std::string& field) {
  check_finite(&v, 1, field);
  return v;
}

Eigen::Quaterniond check_quaternion(const double q[4], const std::string& field) {
  check_finite(q, 4, field);
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  const double norm = quat.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    std::ostringstream s;
    s << field << ": not a unit quaternion [w,x,y,z] (norm " << norm << ")";
    fail("quaternion", s.str());
  }
  return quat.normalized();
}

engine::Pose check_pose(const double p[3], const double q[4], const std::string& prefix,
                        const std::string& pos_name = "position", const std::string& quat_name = "orientation") {
  check_finite(p, 3, prefix + pos_name);
  engine::Pose pose;
  pose.position = Eigen::Vector3d(p[0], p[1], p[2]);
  pose.orientation = check_quaternion(q, prefix + quat_name);
  return pose;
}

// The one positive-definiteness check (estimators/spd_matrix.hpp) over the components that are meaningful: the whole
// matrix symmetric; for planar messages only the x, y, yaw block must be positive definite, the other diagonal
// entries may be zero.
template <int N>
Eigen::Matrix<double, N, N> check_covariance(const double* v, const std::string& field, std::span<const int> active) {
  check_finite(v, N * N, field);
  Eigen::Matrix<double, N, N> m = Eigen::Map<const Eigen::Matrix<double, N, N, Eigen::RowMajor>>(v);
  if (!is_symmetric(m)) fail("covariance", field + ": not symmetric");
  const int k = static_cast<int>(active.size());
  Eigen::MatrixXd sub(k, k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) sub(i, j) = m(active[i], active[j]);
  const DefinitenessCheck check = check_positive_definite(sub);
  if (!check.ok()) {
    std::ostringstream s;
    s << field << ": not positive definite (smallest eigenvalue " << check.smallest_eigenvalue << ")";
    fail("covariance", s.str());
  }
  return m;
}

// A sighting's (range, azimuth, elevation): planar sightings have no elevation.
const std::vector<int> kAll3{0, 1, 2};
const std::vector<int> kPlanar3{0, 1};

template <class Msg>
Decoded decode_as(const void* data, size_t size, MessageOrigin* origin) {
  Msg msg;
  // The layout walk refuses lengths and counts that do not fit before lcm-gen's decode trusts them.
  if (auto e = safe_decode(data, size, msg)) return Rejection{e->reason, e->message};
  if (origin != nullptr) *origin = MessageOrigin{msg.sender, msg.seq};
  return to_event(msg);
}

}  // namespace

Decoded decode_event(InputKind kind, const void* data, size_t size, MessageOrigin* origin) {
  try {
    switch (kind) {
      case InputKind::kOdometry:
        return decode_as<sextant::odometry_t>(data, size, origin);
      case InputKind::kLandmarks:
        return decode_as<sextant::landmarks_t>(data, size, origin);
      case InputKind::kBearings:
        return decode_as<sextant::bearing_scan_t>(data, size, origin);
      case InputKind::kLoopClosures:
        return decode_as<sextant::loop_closure_t>(data, size, origin);
      case InputKind::kImu:
        return decode_as<sextant::imu_t>(data, size, origin);
      case InputKind::kGnss:
        return decode_as<sextant::gnss_t>(data, size, origin);
      case InputKind::kFleet:
        return decode_as<sextant::fleet_contribution_t>(data, size, origin);
      case InputKind::kFleetControl:
        return decode_as<sextant::fleet_control_t>(data, size, origin);
    }
  } catch (const std::exception& e) {
    return Rejection{"decode", std::string("cannot decode: ") + e.what()};
  }
  return Rejection{"invalid", "unknown input kind"};
}

Decoded to_event(const sextant::odometry_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.source, "odometry_t.source");
    if (m.utime <= 0) fail("invalid", "odometry_t.utime: not positive (" + std::to_string(m.utime) + ")");
    engine::Odometry e;
    e.utime = m.utime;
    e.source = m.source;
    e.planar = m.planar;
    e.pose = check_pose(m.position, m.orientation, "odometry_t.");
    const auto active = pose_axes(m.planar);
    e.covariance = check_covariance<6>(m.covariance, "odometry_t.covariance", active);
    if (m.has_increment_covariance)
      e.increment_covariance = check_covariance<6>(m.increment_covariance, "odometry_t.increment_covariance", active);
    if (m.has_twist) {
      engine::Odometry::Twist t;
      check_finite(m.linear_velocity, 3, "odometry_t.linear_velocity");
      check_finite(m.angular_velocity, 3, "odometry_t.angular_velocity");
      t.linear = Eigen::Vector3d(m.linear_velocity[0], m.linear_velocity[1], m.linear_velocity[2]);
      t.angular = Eigen::Vector3d(m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]);
      t.covariance = check_covariance<6>(m.twist_covariance, "odometry_t.twist_covariance", active);
      e.twist = t;
    }
    return engine::Event{std::move(e)};
  });
}

Decoded to_event(const sextant::landmarks_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.source, "landmarks_t.source");
    if (m.utime <= 0) fail("invalid", "landmarks_t.utime: not positive (" + std::to_string(m.utime) + ")");
    if (m.num_observations < 0 || m.num_observations > kMaxObservationsPerMessage)
      fail("too_large", "landmarks_t.num_observations: " + std::to_string(m.num_observations) + " outside [0, " +
                            std::to_string(kMaxObservationsPerMessage) + "]");
    engine::LandmarkSightings e;
    e.utime = m.utime;
    e.source = m.source;
    e.planar = m.planar;
    e.sensor_in_body =
        check_pose(m.sensor_position, m.sensor_orientation, "landmarks_t.", "sensor_position", "sensor_orientation");
    e.observations.reserve(static_cast<size_t>(m.num_observations));
    for (int i = 0; i < m.num_observations; ++i) {
      const auto& o = m.observations[static_cast<size_t>(i)];
      const std::string f = "landmarks_t.observations[" + std::to_string(i) + "].";
      engine::LandmarkObservation ob;
      ob.id = o.id;
      if (o.id < -1) fail("invalid", f + "id: negative (" + std::to_string(o.id) + "); use -1 for unknown");
      ob.range = check_finite(o.range, f + "range");
      if (ob.range <= 0) fail("invalid", f + "range: not positive");
      ob.azimuth = check_finite(o.azimuth, f + "azimuth");
      ob.elevation = m.planar ? 0.0 : check_finite(o.elevation, f + "elevation");
      ob.covariance = check_covariance<3>(o.covariance, f + "covariance", m.planar ? kPlanar3 : kAll3);
      e.observations.push_back(ob);
    }
    return engine::Event{std::move(e)};
  });
}

Decoded to_event(const sextant::bearing_scan_t& m) {
  return guarded([&]() -> Decoded {
    if (m.utime <= 0) fail("invalid", "bearing_scan_t.utime: not positive (" + std::to_string(m.utime) + ")");
    if (m.num_detections < 0 || m.num_detections > kMaxDetectionsPerScan)
      fail("too_large", "bearing_scan_t.num_detections: " + std::to_string(m.num_detections) + " outside [0, " +
                            std::to_string(kMaxDetectionsPerScan) + "]");
    engine::BearingScan e;
    e.utime = m.utime;
    e.sensor_id = m.sensor_id;
    e.scan_id = m.scan_id;
    check_finite(m.sensor_position, 3, "bearing_scan_t.sensor_position");
    e.sensor_position = Eigen::Vector3d(m.sensor_position[0], m.sensor_position[1], m.sensor_position[2]);
    e.detections.reserve(static_cast<size_t>(m.num_detections));
    for (int i = 0; i < m.num_detections; ++i) {
      const auto& d = m.detections[static_cast<size_t>(i)];
      const std::string f = "bearing_scan_t.detections[" + std::to_string(i) + "].";
      engine::BearingDetection b;
      b.azimuth = check_finite(d.azimuth, f + "azimuth");
      b.elevation = check_finite(d.elevation, f + "elevation");
      if (std::abs(b.elevation) > M_PI / 2) fail("invalid", f + "elevation: outside [-pi/2, pi/2]");
      b.sigma_azimuth = check_finite(d.sigma_azimuth, f + "sigma_azimuth");
      b.sigma_elevation = check_finite(d.sigma_elevation, f + "sigma_elevation");
      if (!(b.sigma_azimuth > 0)) fail("covariance", f + "sigma_azimuth: not positive");
      if (!(b.sigma_elevation > 0)) fail("covariance", f + "sigma_elevation: not positive");
      e.detections.push_back(b);
    }
    return engine::Event{std::move(e)};
  });
}

namespace {

// A 3x3 covariance a sensor states: finite, symmetric, positive semi-definite; zero means "not stated".
Eigen::Matrix3d check_stated_covariance(const double* v, const std::string& field) {
  check_finite(v, 9, field);
  const Eigen::Matrix3d m = read_matrix<3>(v);
  if (m.isZero(0)) return m;
  if (!is_symmetric(m)) fail("covariance", field + ": not symmetric");
  const double smallest = smallest_eigenvalue(m), scale = std::max(1.0, m.cwiseAbs().maxCoeff());
  if (smallest < -1e-12 * scale) {
    std::ostringstream s;
    s << field << ": not positive semi-definite (smallest eigenvalue " << smallest << ")";
    fail("covariance", s.str());
  }
  return m;
}

Eigen::Vector3d check_vector3(const double v[3], const std::string& field) {
  check_finite(v, 3, field);
  return {v[0], v[1], v[2]};
}

void check_in(double v, double lo, double hi, const std::string& field) {
  check_finite(v, field);
  if (v < lo || v > hi) {
    std::ostringstream s;
    s << field << ": " << v << " outside [" << lo << ", " << hi << "]";
    fail("invalid", s.str());
  }
}

}  // namespace

Decoded to_event(const sextant::imu_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.source, "imu_t.source");
    check_name(m.frame, "imu_t.frame");
    if (m.utime <= 0) fail("invalid", "imu_t.utime: not positive (" + std::to_string(m.utime) + ")");
    if (!m.has_angular_velocity && !m.has_linear_acceleration && !m.has_orientation)
      fail("invalid", "imu_t: no group present (has_angular_velocity, has_linear_acceleration, has_orientation)");
    engine::ImuSample e;
    e.utime = m.utime;
    e.source = m.source;
    e.frame = m.frame;
    if (m.has_angular_velocity) {
      e.angular_velocity = check_vector3(m.angular_velocity, "imu_t.angular_velocity");
      e.angular_velocity_covariance =
          check_stated_covariance(m.angular_velocity_covariance, "imu_t.angular_velocity_covariance");
    }
    if (m.has_linear_acceleration) {
      e.linear_acceleration = check_vector3(m.linear_acceleration, "imu_t.linear_acceleration");
      e.linear_acceleration_covariance =
          check_stated_covariance(m.linear_acceleration_covariance, "imu_t.linear_acceleration_covariance");
    }
    if (m.has_orientation) {
      e.orientation = check_quaternion(m.orientation, "imu_t.orientation");
      e.orientation_has_yaw = m.orientation_has_yaw;
      e.orientation_covariance = check_stated_covariance(m.orientation_covariance, "imu_t.orientation_covariance");
    }
    return engine::Event{std::move(e)};
  });
}

Decoded to_event(const sextant::gnss_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.source, "gnss_t.source");
    check_name(m.frame, "gnss_t.frame");
    if (m.utime <= 0) fail("invalid", "gnss_t.utime: not positive (" + std::to_string(m.utime) + ")");
    if (m.status == sextant::gnss_t::STATUS_NO_FIX) fail("no_fix", "gnss_t.status: no fix");
    if (m.status < sextant::gnss_t::STATUS_FIX || m.status > sextant::gnss_t::STATUS_RTK_FIXED)
      fail("invalid", "gnss_t.status: unknown value " + std::to_string(m.status));
    engine::GnssFix e;
    e.utime = m.utime;
    e.source = m.source;
    e.frame = m.frame;
    e.status = m.status;
    check_in(m.latitude, -90, 90, "gnss_t.latitude");
    check_in(m.longitude, -180, 180, "gnss_t.longitude");
    check_in(m.altitude, -1e5, 1e5, "gnss_t.altitude");
    e.latitude = m.latitude;
    e.longitude = m.longitude;
    e.altitude = m.altitude;
    e.position_covariance = check_stated_covariance(m.position_covariance, "gnss_t.position_covariance");
    if (m.has_velocity) {
      e.velocity = check_vector3(m.velocity, "gnss_t.velocity");
      e.velocity_covariance = check_stated_covariance(m.velocity_covariance, "gnss_t.velocity_covariance");
    }
    return engine::Event{std::move(e)};
  });
}

Decoded to_event(const sextant::loop_closure_t& m) {
  return guarded([&]() -> Decoded {
    check_name(m.source, "loop_closure_t.source");
    if (!m.source_to.empty()) check_name(m.source_to, "loop_closure_t.source_to");
    if (m.utime <= 0) fail("invalid", "loop_closure_t.utime: not positive (" + std::to_string(m.utime) + ")");
    if (m.utime_from <= 0 || m.utime_to <= 0) fail("invalid", "loop_closure_t.utime_from/utime_to: not positive");
    if (m.utime_from == m.utime_to && (m.source_to.empty() || m.source_to == m.source))
      fail("invalid", "loop_closure_t.utime_to: equal to utime_from (one body)");
    engine::LoopClosure e;
    e.utime = m.utime;
    e.source = m.source;
    if (m.source_to != m.source) e.source_to = m.source_to;
    e.planar = m.planar;
    e.utime_from = m.utime_from;
    e.utime_to = m.utime_to;
    e.keyframe_from = m.keyframe_from;
    e.keyframe_to = m.keyframe_to;
    e.request_id = m.request_id;
    e.relative = check_pose(m.position, m.orientation, "loop_closure_t.");
    e.information = check_covariance<6>(m.information, "loop_closure_t.information", pose_axes(m.planar));
    e.matcher = m.matcher;
    e.score = check_finite(m.score, "loop_closure_t.score");
    return engine::Event{std::move(e)};
  });
}

sextant::odometry_t to_message(const engine::Odometry& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::odometry_t>(e.utime, sender, seq);
  m.source = e.source;
  m.planar = e.planar;
  copy_pose(e.pose, m.position, m.orientation);
  copy_row_major<6>(e.covariance, m.covariance);
  m.has_increment_covariance = e.increment_covariance.has_value();
  copy_row_major<6>(e.increment_covariance.value_or(engine::Matrix6::Zero()), m.increment_covariance);
  m.has_twist = e.twist.has_value();
  const engine::Odometry::Twist twist = e.twist.value_or(engine::Odometry::Twist{});
  for (int i = 0; i < 3; ++i) {
    m.linear_velocity[i] = twist.linear[i];
    m.angular_velocity[i] = twist.angular[i];
  }
  copy_row_major<6>(twist.covariance, m.twist_covariance);
  return m;
}

sextant::landmarks_t to_message(const engine::LandmarkSightings& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::landmarks_t>(e.utime, sender, seq);
  m.source = e.source;
  m.planar = e.planar;
  copy_pose(e.sensor_in_body, m.sensor_position, m.sensor_orientation);
  m.num_observations = static_cast<int32_t>(e.observations.size());
  for (const auto& o : e.observations) {
    sextant::landmark_observation_t x{};
    x.id = o.id;
    x.range = o.range;
    x.azimuth = o.azimuth;
    x.elevation = o.elevation;
    copy_row_major<3>(o.covariance, x.covariance);
    m.observations.push_back(x);
  }
  return m;
}

sextant::bearing_scan_t to_message(const engine::BearingScan& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::bearing_scan_t>(e.utime, sender, seq);
  m.sensor_id = e.sensor_id;
  for (int i = 0; i < 3; ++i) m.sensor_position[i] = e.sensor_position[i];
  m.scan_id = e.scan_id;
  m.num_detections = static_cast<int32_t>(e.detections.size());
  for (const auto& d : e.detections) {
    sextant::bearing_detection_t x{};
    x.azimuth = d.azimuth;
    x.elevation = d.elevation;
    x.sigma_azimuth = d.sigma_azimuth;
    x.sigma_elevation = d.sigma_elevation;
    m.detections.push_back(x);
  }
  return m;
}

sextant::loop_closure_t to_message(const engine::LoopClosure& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::loop_closure_t>(e.utime, sender, seq);
  m.source = e.source;
  m.source_to = e.source_to;
  m.planar = e.planar;
  m.utime_from = e.utime_from;
  m.utime_to = e.utime_to;
  m.keyframe_from = e.keyframe_from;
  m.keyframe_to = e.keyframe_to;
  m.request_id = e.request_id;
  copy_pose(e.relative, m.position, m.orientation);
  copy_row_major<6>(e.information, m.information);
  m.matcher = e.matcher;
  m.score = e.score;
  return m;
}

sextant::imu_t to_message(const engine::ImuSample& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::imu_t>(e.utime, sender, seq);
  m.source = e.source;
  m.frame = e.frame;
  m.has_angular_velocity = e.angular_velocity.has_value();
  if (e.angular_velocity) std::copy(e.angular_velocity->data(), e.angular_velocity->data() + 3, m.angular_velocity);
  copy_row_major<3>(e.angular_velocity_covariance, m.angular_velocity_covariance);
  m.has_linear_acceleration = e.linear_acceleration.has_value();
  if (e.linear_acceleration)
    std::copy(e.linear_acceleration->data(), e.linear_acceleration->data() + 3, m.linear_acceleration);
  copy_row_major<3>(e.linear_acceleration_covariance, m.linear_acceleration_covariance);
  m.has_orientation = e.orientation.has_value();
  m.orientation_has_yaw = e.orientation_has_yaw;
  const Eigen::Quaterniond q = e.orientation.value_or(Eigen::Quaterniond::Identity()).normalized();
  m.orientation[0] = q.w(), m.orientation[1] = q.x(), m.orientation[2] = q.y(), m.orientation[3] = q.z();
  copy_row_major<3>(e.orientation_covariance, m.orientation_covariance);
  return m;
}

sextant::gnss_t to_message(const engine::GnssFix& e, const std::string& sender, int64_t seq) {
  auto m = message_header<sextant::gnss_t>(e.utime, sender, seq);
  m.source = e.source;
  m.frame = e.frame;
  m.status = static_cast<int8_t>(e.status);
  m.latitude = e.latitude;
  m.longitude = e.longitude;
  m.altitude = e.altitude;
  m.covariance_type = sextant::gnss_t::COVARIANCE_KNOWN;
  copy_row_major<3>(e.position_covariance, m.position_covariance);
  m.has_velocity = e.velocity.has_value();
  if (e.velocity) std::copy(e.velocity->data(), e.velocity->data() + 3, m.velocity);
  copy_row_major<3>(e.velocity_covariance, m.velocity_covariance);
  return m;
}

}  // namespace sextant::runtime
