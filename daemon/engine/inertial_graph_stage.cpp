#include "daemon/engine/inertial_graph_stage.hpp"
#include "daemon/engine/geo_pose.hpp"

#include "daemon/engine/pose_covariance.hpp"
#include "estimators/inertial/gnss_realign.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>

namespace sextant::engine {
namespace {

// The smoother's options from the stage's section.
inertial::InertialSmootherOptions smoother_options(const InertialConfig& c) {
  inertial::InertialSmootherOptions o;
  o.noise.gyro_noise_density = c.gyro_noise_density;
  o.noise.accel_noise_density = c.accel_noise_density;
  // The smoother's bias random-walk factors need a positive density; the filter's section allows 0 (a constant bias).
  o.noise.gyro_bias_random_walk = std::max(c.gyro_bias_random_walk, 1e-9);
  o.noise.accel_bias_random_walk = std::max(c.accel_bias_random_walk, 1e-9);
  o.keyframe_interval = c.graph.keyframe_interval;
  o.window = c.graph.window;
  o.gnss_kernel_width = c.graph.gnss_kernel_width;
  o.initial_gyro_bias_sigma = c.initial_sigma_gyro_bias;
  o.initial_accel_bias_sigma = c.initial_sigma_accel_bias;
  o.initial_yaw_sigma = c.graph.initial_yaw_sigma;
  return o;
}

// A planar source states nothing about z, roll and pitch: a ground robot does not move along its own z axis (z gets
// the larger of the x and y variances), and its roll and pitch follow the ground (0.1 rad per increment).
Matrix6 odometry_increment_covariance(const Odometry& o, const SE3& delta, const Matrix6& previous_pose_covariance) {
  Matrix6 q = increment_covariance(o, delta, previous_pose_covariance, 1e-10);
  if (o.planar) {
    const double z = std::max(q(0, 0), q(1, 1));
    for (int i : {2, 3, 4}) q.row(i).setZero(), q.col(i).setZero();
    q(2, 2) = z, q(3, 3) = q(4, 4) = 0.01;
  }
  return q;
}

}  // namespace

InertialGraphStage::InertialGraphStage(InertialConfig config)
    : config_(std::move(config)), options_(smoother_options(config_)), mountings_(config_.mountings) {
  inertial::check_options(options_);
}

bool InertialGraphStage::accepts(const Event& e) const {
  return std::holds_alternative<ImuSample>(e) || std::holds_alternative<GnssFix>(e) ||
         std::holds_alternative<Odometry>(e);
}

void InertialGraphStage::handle(const Event& e, const Emit& emit) {
  if (const auto* s = std::get_if<ImuSample>(&e))
    on_imu(*s, emit);
  else if (const auto* o = std::get_if<Odometry>(&e))
    on_odometry(*o);
  else if (const auto* g = std::get_if<GnssFix>(&e))
    on_gnss(*g);
}

void InertialGraphStage::on_imu(const ImuSample& s, const Emit& emit) {
  const inertial::SensorMounting* m = mountings_.find(s.source, s.frame);
  if (m == nullptr) {
    ++unmounted_;
    return;
  }
  if (!s.angular_velocity || !s.linear_acceleration) return;  // the smoother predicts; orientation-only units do not
  Body& b = bodies_[s.source];
  if (!b.smoother) {
    b.first_imu = s;
    return;
  }
  b.smoother->add_imu(seconds(b, s.utime), inertial::imu_to_body(*m, *s.angular_velocity, *s.linear_acceleration));
  refresh(b);
  publish(s.source, b, s.utime, emit);
}

void InertialGraphStage::start(Body& b, const Odometry& o) {
  const ImuSample& s = *b.first_imu;
  const inertial::SensorMounting& m = *mountings_.find(s.source, s.frame);
  inertial::NavState x;
  x.R = initial_orientation(s, m, inertial::imu_to_body(m, *s.angular_velocity, *s.linear_acceleration))
            .toRotationMatrix();
  if (o.twist) x.v = x.R * o.twist->linear;
  b.t0 = o.utime;
  b.yaw_known = yaw_known_in_enu(config_, s);
  b.smoother.emplace(options_);
  b.smoother->initialize(0, x, {}, SE3(SO3::from_unit_quaternion(o.pose.orientation), o.pose.position));
  ++started_;
}

void InertialGraphStage::on_odometry(const Odometry& o) {
  auto it = bodies_.find(o.source);
  if (it == bodies_.end() || !it->second.first_imu) return;  // an IMU sample comes first
  Body& b = it->second;
  const SE3 pose(SO3::from_unit_quaternion(o.pose.orientation.normalized()), o.pose.position);
  if (!b.smoother) {
    start(b, o);
  } else if (b.last_odometry) {
    const SE3 delta = b.last_odometry->inverse() * pose;
    b.smoother->add_odometry(seconds(b, o.utime), pose,
                             odometry_increment_covariance(o, delta, b.last_odometry_covariance));
    refresh(b);
  }
  b.last_odometry = pose;
  b.last_odometry_covariance = o.covariance;
}

void InertialGraphStage::on_gnss(const GnssFix& g) {
  auto it = bodies_.find(g.source);
  if (it == bodies_.end() || !it->second.smoother) return;
  Body& b = it->second;
  const inertial::SensorMounting* m = mountings_.find(g.source, g.frame);
  if (m == nullptr) {
    ++unmounted_;
    return;
  }
  const geodesy::Geodetic fix{g.latitude, g.longitude, g.altitude};
  if (!b.plane) {
    const bool configured = config_.datum.size() == 3;
    b.plane.emplace(configured ? geodesy::Geodetic{config_.datum[0], config_.datum[1], config_.datum[2]} : fix);
  }
  const Eigen::Matrix3d to_plane = b.plane->enu_at(fix);
  const Eigen::Vector3d z = b.plane->to_enu(fix);
  const double t = seconds(b, g.utime);
  Eigen::Matrix3d R =
      to_plane * stated_or_default(g.position_covariance, config_.default_gnss_variance) * to_plane.transpose();
  if (!b.anchored) {
    anchor(b, t, z, m->lever_arm);
    if (!b.anchored || b.yaw_known) return;
    b.heading.emplace(gnss_heading_options(config_));
  }
  if (b.heading) return wait_for_heading(b, t, z, R, m->lever_arm);
  for (int i = 0; i < 3; ++i)  // gnss_position: a component not selected carries no information
    if (!config_.gnss_position[static_cast<size_t>(i)]) R.row(i).setZero(), R.col(i).setZero(), R(i, i) = 1e8;
  b.smoother->add_gnss(t, z, R, m->lever_arm);
}

void InertialGraphStage::anchor(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Vector3d& lever) {
  if (t < b.smoother->current_time()) return;  // a fix older than the state: wait for the next
  inertial::NavState x = b.smoother->current();
  x.p = antenna - x.R * lever;
  const inertial::ImuBias bias = b.smoother->newest().bias;
  b.smoother->initialize(t, x, bias);
  b.anchored = true;
  ++anchored_;
}

void InertialGraphStage::wait_for_heading(Body& b, double t, const Eigen::Vector3d& antenna, const Eigen::Matrix3d& R,
                                          const Eigen::Vector3d& lever) {
  const inertial::NavState x = b.smoother->current();
  const Eigen::Vector3d track = x.p + x.v * (t - b.smoother->current_time()) + x.R * lever;
  const auto a = b.heading->add(track.head<2>(), antenna.head<2>(), R.topLeftCorner<2, 2>());
  if (!a) return;
  const double position_sigma = std::sqrt(
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(a->covariance_at(x.p.head<2>())).eigenvalues().maxCoeff());
  b.smoother->initialize(b.smoother->current_time(), inertial::realigned(*a, x), b.smoother->newest().bias,
                         std::nullopt,
                         inertial::InertialSmoother::PriorSigmas{std::max(position_sigma, 0.1), a->yaw_sigma});
  b.heading.reset();
  ++heading_aligned_;
}

void InertialGraphStage::refresh(Body& b) {
  const int64_t k = b.smoother->counters().keyframes;
  if (k == b.keyframes) return;
  b.keyframes = k;
  const Matrix6d c = b.smoother->newest_pose_covariance();  // [rho; phi]: sextant's right perturbation already
  b.covariance = c;
  b.observability = inertial::observability_of(c, b.smoother->newest().state.R, options_);
}

void InertialGraphStage::publish(const std::string& source, Body& b, int64_t utime, const Emit& emit) {
  const auto period = static_cast<int64_t>(1e6 / std::max(config_.publish_rate_hz, 1e-6));
  if (b.last_published != 0 && utime - b.last_published < period) return;
  const inertial::NavState x = b.smoother->current();
  if (!x.p.allFinite() || !x.R.allFinite() || !b.covariance.allFinite()) return;
  FusedPose out;
  out.utime = utime;
  out.source = source;
  out.estimator = estimator();
  out.pose.position = x.p;
  out.pose.orientation = Eigen::Quaterniond(x.R).normalized();
  out.covariance = b.covariance;
  b.last_published = utime;
  ++published_;
  emit(out);
  if (b.plane) emit(to_geo_pose(out, *b.plane, !b.heading));
}

Counters InertialGraphStage::counters() const {
  int64_t keyframes = 0, links = 0, down_weighted = 0, dropped = 0, failed = 0, restarts = 0, tilt = 0, yaw = 0,
          waiting = 0;
  for (const auto& [name, b] : bodies_) {
    waiting += b.heading ? 1 : 0;
    if (!b.smoother) continue;
    const auto& c = b.smoother->counters();
    keyframes += c.keyframes, links += c.odometry_links, down_weighted += c.gnss_down_weighted, dropped += c.dropped,
        failed += c.failed_solves, restarts += c.restarts;
    tilt += b.observability.tilt ? 1 : 0, yaw += b.observability.yaw ? 1 : 0;
  }
  return {{"bodies", static_cast<int64_t>(bodies_.size())},
          {"started", started_},
          {"gnss_anchored", anchored_},
          {"gnss_heading_waiting", waiting},
          {"gnss_heading_aligned", heading_aligned_},
          {"unmounted", unmounted_},
          {"keyframes", keyframes},
          {"odometry_links", links},
          {"gnss_down_weighted", down_weighted},
          {"dropped", dropped},
          {"failed_solves", failed},
          {"restarts", restarts},
          {"tilt_observable", tilt},
          {"yaw_observable", yaw},
          {"published", published_}};
}

}  // namespace sextant::engine
