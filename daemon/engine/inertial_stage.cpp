#include "daemon/engine/inertial_stage.hpp"
#include "daemon/engine/geo_pose.hpp"

#include "estimators/inertial/gnss_realign.hpp"
#include "estimators/lie/pose_covariance.hpp"

#include <cmath>
#include <stdexcept>

namespace sextant::engine {

InertialStage::InertialStage(InertialConfig config) : config_(std::move(config)), mountings_(config_.mountings) {
  options_.noise.gyro_noise_density = config_.gyro_noise_density;
  options_.noise.accel_noise_density = config_.accel_noise_density;
  options_.noise.gyro_bias_random_walk = config_.gyro_bias_random_walk;
  options_.noise.accel_bias_random_walk = config_.accel_bias_random_walk;
}

bool InertialStage::accepts(const Event& e) const {
  if (std::holds_alternative<ImuSample>(e) || std::holds_alternative<GnssFix>(e)) return true;
  if (const auto* o = std::get_if<Odometry>(&e)) return o->twist.has_value();
  return false;
}

const inertial::SensorMounting* InertialStage::mounting(const std::string& source, const std::string& frame) const {
  return mountings_.find(source, frame);
}

void InertialStage::handle(const Event& e, const Emit& emit) {
  if (const auto* s = std::get_if<ImuSample>(&e))
    on_imu(*s, emit);
  else if (const auto* o = std::get_if<Odometry>(&e))
    on_odometry(*o);
  else if (const auto* g = std::get_if<GnssFix>(&e))
    on_gnss(*g);
}

void InertialStage::count(const filter::UpdateResult& r) {
  if (r.accepted)
    ++updates_;
  else if (r.reason == filter::UpdateReason::kGate)
    ++gated_;
  else if (r.reason == filter::UpdateReason::kTooOld)
    ++too_old_;
  else
    ++refused_;
}

void InertialStage::start(Body& b, const ImuSample& s, const inertial::SensorMounting& m) {
  const inertial::BodyImuSample body = inertial::imu_to_body(m, *s.angular_velocity, *s.linear_acceleration);
  inertial::EskfState x;
  x.q = initial_orientation(s, m, body);
  inertial::ErrorStateEkf::Matrix15 P = inertial::ErrorStateEkf::Matrix15::Zero();
  const double sa = config_.initial_sigma_accel_bias, sg = config_.initial_sigma_gyro_bias;
  P.diagonal() << Eigen::Vector3d::Constant(1e-9), Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(1e-3),
      Eigen::Vector3d::Constant(sa * sa), Eigen::Vector3d::Constant(sg * sg);
  b.t0 = s.utime;
  b.yaw_known = yaw_known_in_enu(config_, s);
  b.filter = std::make_unique<inertial::LaggedEskf>(options_, config_.history_s);
  b.filter->initialize(0, x, P);
  ++started_;
}

void InertialStage::on_imu(const ImuSample& s, const Emit& emit) {
  ++imu_;
  const inertial::SensorMounting* m = mounting(s.source, s.frame);
  if (m == nullptr) {
    ++unmounted_;
    return;
  }
  Body& b = bodies_[s.source];
  const bool predicts = s.angular_velocity && s.linear_acceleration;
  if (!b.filter) {
    if (!predicts) {
      ++no_filter_yet_;
      return;
    }
    start(b, s, *m);
  }
  const double t = seconds(b, s.utime);
  if (predicts) {
    const auto r = b.filter->add_imu(t, inertial::imu_to_body(*m, *s.angular_velocity, *s.linear_acceleration));
    if (r != inertial::ImuResult::propagated && r != inertial::ImuResult::started) ++imu_refused_;
  }
  if (s.orientation) {
    inertial::FieldMask fields = config_.imu_orientation;
    fields[2] = fields[2] && s.orientation_has_yaw;
    const Eigen::Quaterniond q = *s.orientation;
    const Eigen::Matrix3d R = stated_or_default(s.orientation_covariance, config_.default_orientation_variance);
    const inertial::SensorMounting mount = *m;
    count(b.filter->add_measurement(
        t, [q, R, mount, fields](inertial::ErrorStateEkf& f) { return f.update_orientation(q, R, mount, fields); }));
  }
  publish(s.source, b, s.utime, emit);
}

void InertialStage::on_odometry(const Odometry& o) {
  auto it = bodies_.find(o.source);
  if (it == bodies_.end() || !it->second.filter) return;  // the IMU starts a body's filter
  Body& b = it->second;
  const Eigen::Vector3d v = o.twist->linear;
  const Eigen::Matrix3d R =
      stated_or_default(o.twist->covariance.topLeftCorner<3, 3>(), config_.default_velocity_variance);
  const inertial::FieldMask fields = config_.odometry_velocity;
  count(b.filter->add_measurement(seconds(b, o.utime), [v, R, fields](inertial::ErrorStateEkf& f) {
    return f.update_body_velocity(v, R, inertial::SensorMounting{}, fields);
  }));
}

void InertialStage::on_gnss(const GnssFix& g) {
  auto it = bodies_.find(g.source);
  if (it == bodies_.end() || !it->second.filter) return;
  Body& b = it->second;
  const inertial::SensorMounting* m = mounting(g.source, g.frame);
  if (m == nullptr) {
    ++unmounted_;
    return;
  }
  const geodesy::Geodetic fix{g.latitude, g.longitude, g.altitude};
  const bool first = !b.plane;
  if (first) {
    const bool configured = config_.datum.size() == 3;
    b.plane.emplace(configured ? geodesy::Geodetic{config_.datum[0], config_.datum[1], config_.datum[2]} : fix);
  }
  const Eigen::Matrix3d to_plane = b.plane->enu_at(fix);
  const Eigen::Vector3d z = b.plane->to_enu(fix);
  const Eigen::Matrix3d R =
      to_plane * stated_or_default(g.position_covariance, config_.default_gnss_variance) * to_plane.transpose();
  const Eigen::Vector3d lever = m->lever_arm;
  const double t = seconds(b, g.utime);
  if (first) {
    anchor(b, z, R, lever);
    if (!b.yaw_known) b.heading.emplace(gnss_heading_options(config_));
  }
  if (b.heading) return wait_for_heading(b, t, z, R, lever);
  if (first) return;
  const inertial::FieldMask fields = config_.gnss_position;
  const double gate = config_.gnss_gate;
  count_fix(b, b.filter->add_measurement(t, [z, R, lever, fields, gate](inertial::ErrorStateEkf& f) {
    return f.update_gnss_position(z, R, lever, fields, gate);
  }));
  if (g.velocity && (config_.gnss_velocity[0] || config_.gnss_velocity[1] || config_.gnss_velocity[2])) {
    const Eigen::Vector3d v = to_plane * *g.velocity;
    const Eigen::Matrix3d Rv =
        to_plane * stated_or_default(g.velocity_covariance, config_.default_velocity_variance) * to_plane.transpose();
    const inertial::FieldMask vfields = config_.gnss_velocity;
    count(b.filter->add_measurement(t, [v, Rv, lever, vfields](inertial::ErrorStateEkf& f) {
      return f.update_gnss_velocity(v, Rv, lever, vfields);
    }));
  }
}

void InertialStage::anchor(Body& b, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R,
                           const Eigen::Vector3d& lever) {
  const inertial::ErrorStateEkf& f = b.filter->filter();
  inertial::EskfState x = f.state();
  x.p = antenna - x.q * lever;
  inertial::ErrorStateEkf::Matrix15 P = f.covariance();
  using E = inertial::ErrorStateEkf;
  P.block<3, E::kDim>(E::kP, 0).setZero();
  P.block<E::kDim, 3>(0, E::kP).setZero();
  P.block<3, 3>(E::kP, E::kP) = R;
  b.filter->initialize(f.time(), x, P);
  ++anchored_;
}

void InertialStage::count_fix(Body& b, const filter::UpdateResult& r) {
  count(r);
  b.consecutive_gated = r.reason == filter::UpdateReason::kGate ? b.consecutive_gated + 1 : 0;
  const int limit = config_.gnss_heading.reacquire_after;
  if (limit == 0 || b.consecutive_gated < limit || config_.gnss_heading.align == GnssHeadingConfig::Align::kNever)
    return;
  b.heading.emplace(gnss_heading_options(config_));
  b.consecutive_gated = 0;
  ++reacquired_;
}

void InertialStage::wait_for_heading(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R,
                                     const Eigen::Vector3d& lever) {
  const inertial::ErrorStateEkf& f = b.filter->filter();
  const inertial::EskfState& x = f.state();
  const Eigen::Vector3d track = x.p + x.v * (t - f.time()) + x.q * lever;
  const auto a = b.heading->add(track.head<2>(), antenna.head<2>(), R.topLeftCorner<2, 2>());
  if (!a) return;
  b.filter->initialize(f.time(), inertial::realigned(*a, x), inertial::realigned_covariance(*a, x, f.covariance()));
  b.heading.reset();
  ++heading_aligned_;
}

void InertialStage::publish(const std::string& source, Body& b, int64_t utime, const Emit& emit) {
  const auto period = static_cast<int64_t>(1e6 / std::max(config_.publish_rate_hz, 1e-6));
  if (b.last_published != 0 && utime - b.last_published < period) return;
  const inertial::ErrorStateEkf& f = b.filter->filter();
  const auto& x = f.state();
  if (!x.p.allFinite() || !x.q.coeffs().allFinite() || !f.covariance().allFinite()) return;
  FusedPose out;
  out.utime = utime;
  out.source = source;
  out.estimator = "inertial";
  out.pose.position = x.p;
  out.pose.orientation = x.q.normalized();
  using E = inertial::ErrorStateEkf;
  Matrix6 world;  // the filter's [dp world; theta body]
  world.topLeftCorner<3, 3>() = f.covariance().block<3, 3>(E::kP, E::kP);
  world.topRightCorner<3, 3>() = f.covariance().block<3, 3>(E::kP, E::kTheta);
  world.bottomLeftCorner<3, 3>() = f.covariance().block<3, 3>(E::kTheta, E::kP);
  world.bottomRightCorner<3, 3>() = f.covariance().block<3, 3>(E::kTheta, E::kTheta);
  out.covariance = right_perturbation_from_world_position(x.q.normalized().toRotationMatrix(), world);
  b.last_published = utime;
  ++published_;
  emit(out);
  if (b.plane) emit(to_geo_pose(out, *b.plane, !b.heading));
}

Counters InertialStage::counters() const {
  int64_t waiting = 0;
  for (const auto& [name, b] : bodies_) waiting += b.heading ? 1 : 0;
  return {{"bodies", static_cast<int64_t>(bodies_.size())},
          {"imu_samples", imu_},
          {"started", started_},
          {"gnss_anchored", anchored_},
          {"gnss_heading_waiting", waiting},
          {"gnss_heading_aligned", heading_aligned_},
          {"gnss_heading_reacquired", reacquired_},
          {"unmounted", unmounted_},
          {"before_start", no_filter_yet_},
          {"imu_refused", imu_refused_},
          {"updates", updates_},
          {"updates_refused", refused_},
          {"updates_gated", gated_},
          {"updates_too_old", too_old_},
          {"published", published_}};
}

}  // namespace sextant::engine
