#include "daemon/runtime/plausibility.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace sextant::runtime {
namespace {

Rejection implausible(const std::string& what, const std::string& message) {
  return Rejection{"implausible_" + what, message};
}

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::optional<Rejection> check_position(const Eigen::Vector3d& p, const config::Plausibility& l,
                                        const std::string& field) {
  if (p.norm() <= l.max_position_m) return std::nullopt;
  return implausible("position", field + ": " + number(p.norm()) + " m from the origin (max_position_m " +
                                     number(l.max_position_m) + ")");
}

// The angle between the body's z axis and the plane's normal: the roll/pitch a planar message must not have.
double tilt(const Eigen::Quaterniond& q) { return std::acos(std::clamp(q.toRotationMatrix()(2, 2), -1.0, 1.0)); }

std::optional<Rejection> check_tilt(bool planar, const Eigen::Quaterniond& q, const config::Plausibility& l,
                                    const std::string& field) {
  if (!planar || tilt(q) <= l.max_planar_tilt_rad) return std::nullopt;
  return implausible("tilt", field + ": roll/pitch of " + number(tilt(q)) +
                                 " rad in a planar message (max_planar_tilt_rad " + number(l.max_planar_tilt_rad) +
                                 ")");
}

// The eigenvalues of the meaningful block (`active` rows and columns) against the variance and condition bounds;
// `inverse`: the matrix is an information matrix, its eigenvalues are inverse variances.
template <int N>
std::optional<Rejection> check_spread(const Eigen::Matrix<double, N, N>& m, const std::vector<int>& active,
                                      const config::Plausibility& l, const std::string& field, bool inverse = false) {
  const auto k = static_cast<Eigen::Index>(active.size());
  Eigen::MatrixXd sub(k, k);
  for (Eigen::Index i = 0; i < k; ++i)
    for (Eigen::Index j = 0; j < k; ++j) sub(i, j) = m(active[static_cast<size_t>(i)], active[static_cast<size_t>(j)]);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sub, Eigen::EigenvaluesOnly);
  double lo = eig.eigenvalues().minCoeff(), hi = eig.eigenvalues().maxCoeff();
  if (inverse) std::tie(lo, hi) = std::pair{1.0 / hi, 1.0 / lo};
  std::string why;
  if (!(lo >= l.min_variance))
    why = "smallest variance " + number(lo) + " below min_variance " + number(l.min_variance);
  else if (!(hi <= l.max_variance))
    why = "largest variance " + number(hi) + " above max_variance " + number(l.max_variance);
  else if (!(hi <= l.max_condition * lo))
    why = "condition number " + number(hi / lo) + " above max_condition " + number(l.max_condition);
  if (why.empty()) return std::nullopt;
  return implausible("covariance", field + ": " + why + (inverse ? " (of its inverse)" : ""));
}

std::vector<int> pose_active(bool planar) {
  return planar ? std::vector<int>{0, 1, 5} : std::vector<int>{0, 1, 2, 3, 4, 5};
}

}  // namespace

Plausibility::Plausibility(config::Plausibility limits, int resync_messages, size_t max_streams)
    : limits_(limits), resync_messages_(std::max(resync_messages, 1)), max_streams_(std::max<size_t>(max_streams, 1)) {}

std::optional<Rejection> Plausibility::check(const std::string& stream, const engine::Event& event) {
  resynced_ = false;
  const config::Plausibility& l = limits_;
  if (const auto* o = std::get_if<engine::Odometry>(&event)) return check_odometry(stream, *o);
  if (const auto* s = std::get_if<engine::LandmarkSightings>(&event)) {
    if (auto r = check_position(s->sensor_in_body.position, l, "landmarks_t.sensor_position")) return r;
    if (auto r = check_tilt(s->planar, s->sensor_in_body.orientation, l, "landmarks_t.sensor_orientation")) return r;
    const std::vector<int> active = s->planar ? std::vector<int>{0, 1} : std::vector<int>{0, 1, 2};
    for (size_t i = 0; i < s->observations.size(); ++i) {
      const auto& ob = s->observations[i];
      const std::string f = "landmarks_t.observations[" + std::to_string(i) + "].";
      if (ob.range > l.max_range_m)
        return implausible("range",
                           f + "range: " + number(ob.range) + " m (max_range_m " + number(l.max_range_m) + ")");
      if (auto r = check_spread<3>(ob.covariance, active, l, f + "covariance")) return r;
    }
    return std::nullopt;
  }
  if (const auto* b = std::get_if<engine::BearingScan>(&event)) {
    if (auto r = check_position(b->sensor_position, l, "bearing_scan_t.sensor_position")) return r;
    for (size_t i = 0; i < b->detections.size(); ++i) {
      const auto& d = b->detections[i];
      const Eigen::Matrix2d c =
          Eigen::Vector2d(d.sigma_azimuth * d.sigma_azimuth, d.sigma_elevation * d.sigma_elevation).asDiagonal();
      if (auto r = check_spread<2>(c, {0, 1}, l, "bearing_scan_t.detections[" + std::to_string(i) + "].sigma"))
        return r;
    }
    return std::nullopt;
  }
  if (const auto* m = std::get_if<engine::ImuSample>(&event)) return check_imu(*m);
  if (const auto* g = std::get_if<engine::GnssFix>(&event)) return check_gnss(*g);
  const auto& c = std::get<engine::LoopClosure>(event);
  if (auto r = check_position(c.relative.position, l, "loop_closure_t.position")) return r;
  if (auto r = check_tilt(c.planar, c.relative.orientation, l, "loop_closure_t.orientation")) return r;
  return check_spread<6>(c.information, pose_active(c.planar), l, "loop_closure_t.information", true);
}

std::optional<Rejection> Plausibility::check_imu(const engine::ImuSample& m) const {
  const config::Plausibility& l = limits_;
  if (m.angular_velocity && m.angular_velocity->norm() > l.max_angular_rate_radps)
    return implausible("rate", "imu_t.angular_velocity: " + number(m.angular_velocity->norm()) +
                                   " rad/s (max_angular_rate_radps " + number(l.max_angular_rate_radps) + ")");
  if (m.linear_acceleration && m.linear_acceleration->norm() > l.max_acceleration_mps2)
    return implausible("acceleration", "imu_t.linear_acceleration: " + number(m.linear_acceleration->norm()) +
                                           " m/s^2 (max_acceleration_mps2 " + number(l.max_acceleration_mps2) + ")");
  // A stated covariance (zero means none) must be usable like any other.
  const auto stated = [&](const Eigen::Matrix3d& c, const std::string& f) -> std::optional<Rejection> {
    if (c.isZero(0)) return std::nullopt;
    return check_spread<3>(c, {0, 1, 2}, l, f);
  };
  if (auto r = stated(m.angular_velocity_covariance, "imu_t.angular_velocity_covariance")) return r;
  if (auto r = stated(m.linear_acceleration_covariance, "imu_t.linear_acceleration_covariance")) return r;
  return stated(m.orientation_covariance, "imu_t.orientation_covariance");
}

std::optional<Rejection> Plausibility::check_gnss(const engine::GnssFix& g) const {
  const config::Plausibility& l = limits_;
  if (!g.position_covariance.isZero(0))
    if (auto r = check_spread<3>(g.position_covariance, {0, 1, 2}, l, "gnss_t.position_covariance")) return r;
  if (g.velocity && g.velocity->norm() > l.max_speed_spatial_mps)
    return implausible("speed", "gnss_t.velocity: " + number(g.velocity->norm()) + " m/s (max_speed_spatial_mps " +
                                    number(l.max_speed_spatial_mps) + ")");
  return std::nullopt;
}

std::optional<Rejection> Plausibility::check_odometry(const std::string& stream, const engine::Odometry& o) {
  const config::Plausibility& l = limits_;
  if (auto r = check_position(o.pose.position, l, "odometry_t.position")) return r;
  if (auto r = check_tilt(o.planar, o.pose.orientation, l, "odometry_t.orientation")) return r;
  const std::vector<int> active = pose_active(o.planar);
  if (auto r = check_spread<6>(o.covariance, active, l, "odometry_t.covariance")) return r;
  if (o.increment_covariance)
    if (auto r = check_spread<6>(*o.increment_covariance, active, l, "odometry_t.increment_covariance")) return r;
  if (o.twist) {
    if (auto r = check_spread<6>(o.twist->covariance, active, l, "odometry_t.twist_covariance")) return r;
    const double v = o.twist->linear.norm(), vmax = o.planar ? l.max_speed_planar_mps : l.max_speed_spatial_mps;
    if (v > vmax)
      return implausible("speed", "odometry_t.linear_velocity: " + number(v) + " m/s (max " + number(vmax) + ")");
  }
  return check_speed(stream, o);
}

bool Plausibility::within_speed(int64_t from_utime, const Eigen::Vector3d& from, const engine::Odometry& o) const {
  const double dt = std::max(0.0, static_cast<double>(o.utime - from_utime) * 1e-6);
  const double speed = o.planar ? limits_.max_speed_planar_mps : limits_.max_speed_spatial_mps;
  Eigen::Vector3d d = o.pose.position - from;
  if (o.planar) d.z() = 0;  // planar bodies: x and y only
  return d.norm() <= speed * dt + limits_.max_jump_m;
}

std::optional<Rejection> Plausibility::check_speed(const std::string& stream, const engine::Odometry& o) {
  auto it = motion_.find(stream);
  if (it == motion_.end()) {
    if (motion_.size() >= max_streams_) {  // forget the stream seen least recently
      auto oldest = std::min_element(motion_.begin(), motion_.end(),
                                     [](const auto& a, const auto& b) { return a.second.utime < b.second.utime; });
      motion_.erase(oldest);
    }
    motion_[stream] = Motion{o.utime, o.pose.position, 0, 0, {}};
    return std::nullopt;
  }
  Motion& m = it->second;
  if (within_speed(m.utime, m.position, o)) {
    m = Motion{o.utime, o.pose.position, 0, 0, {}};
    return std::nullopt;
  }
  // A run of refused messages that are plausible among themselves is a reset of the sender's odometry frame.
  const bool continues = m.refused_in_row > 0 && within_speed(m.refused_utime, m.refused_position, o);
  m.refused_in_row = continues ? m.refused_in_row + 1 : 1;
  m.refused_utime = o.utime;
  m.refused_position = o.pose.position;
  if (m.refused_in_row > resync_messages_) {
    m = Motion{o.utime, o.pose.position, 0, 0, {}};
    resynced_ = true;
    return std::nullopt;
  }
  const double dt = static_cast<double>(o.utime - m.utime) * 1e-6;
  return implausible("speed", "odometry_t.position: moved " + number((o.pose.position - m.position).norm()) + " m in " +
                                  number(dt) + " s (max " +
                                  number(o.planar ? limits_.max_speed_planar_mps : limits_.max_speed_spatial_mps) +
                                  " m/s + max_jump_m " + number(limits_.max_jump_m) + ")");
}

}  // namespace sextant::runtime
