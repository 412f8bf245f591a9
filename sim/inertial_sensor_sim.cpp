#include "sim/inertial_sensor_sim.hpp"

#include "estimators/lie/so3.hpp"
#include "estimators/random/portable_random.hpp"

#include <cmath>
#include <utility>

namespace sextant::tools {
namespace {

constexpr double kH = 1e-3;  // s, the step of the central differences

Eigen::Vector3d body_rate(const TruthFunction& truth, double t) {
  const Eigen::Matrix3d a = truth(t - kH).linear(), b = truth(t + kH).linear();
  return SO3(Eigen::Matrix3d(a.transpose() * b)).log() / (2 * kH);
}

}  // namespace

InertialSensorSimulator::InertialSensorSimulator(TruthFunction truth, const SimulatedImuOptions& imu,
                                                 const SimulatedGnssOptions& gnss, uint64_t seed)
    : truth_(std::move(truth)), imu_(imu), gnss_(gnss), plane_(gnss.datum), rng_(seed) {
  imu_.mounting.check("simulated IMU mounting");
  b_g_ = gauss3(imu_.initial_gyro_bias_sigma, imu_.initial_gyro_bias_sigma, imu_.initial_gyro_bias_sigma);
  b_a_ = gauss3(imu_.initial_accel_bias_sigma, imu_.initial_accel_bias_sigma, imu_.initial_accel_bias_sigma);
}

Eigen::Vector3d InertialSensorSimulator::gauss3(double sx, double sy, double sz) {
  const double x = random::standard_normal(rng_), y = random::standard_normal(rng_), z = random::standard_normal(rng_);
  return {sx * x, sy * y, sz * z};
}

TrueMotion InertialSensorSimulator::true_motion(const TruthFunction& truth, double t, const Eigen::Vector3d& gravity) {
  const Eigen::Isometry3d T = truth(t);
  const Eigen::Vector3d p0 = truth(t - kH).translation(), p1 = T.translation(), p2 = truth(t + kH).translation();
  TrueMotion m;
  m.velocity = (p2 - p0) / (2 * kH);
  const Eigen::Vector3d a = (p2 - 2 * p1 + p0) / (kH * kH);
  m.specific_force = T.linear().transpose() * (a - gravity);
  m.angular_velocity = body_rate(truth, t);
  m.angular_acceleration = (body_rate(truth, t + kH) - body_rate(truth, t - kH)) / (2 * kH);
  return m;
}

ImuReading InertialSensorSimulator::imu(double t) {
  if (last_imu_t_ && t > *last_imu_t_) {
    const double dt = t - *last_imu_t_;
    const double sg = imu_.noise.gyro_bias_random_walk * std::sqrt(dt),
                 sa = imu_.noise.accel_bias_random_walk * std::sqrt(dt);
    b_g_ += gauss3(sg, sg, sg);
    b_a_ += gauss3(sa, sa, sa);
  }
  last_imu_t_ = t;
  const TrueMotion m = true_motion(truth_, t, imu_.gravity);
  const Eigen::Matrix3d& R_bs = imu_.mounting.rotation;
  const Eigen::Vector3d& l = imu_.mounting.lever_arm;
  const Eigen::Vector3d& w = m.angular_velocity;
  const double ng = imu_.noise.gyro_noise_density * std::sqrt(imu_.rate_hz);
  const double na = imu_.noise.accel_noise_density * std::sqrt(imu_.rate_hz);
  ImuReading r;
  r.t = t;
  r.gyro = R_bs.transpose() * w + b_g_ + gauss3(ng, ng, ng);
  r.accel = R_bs.transpose() * (m.specific_force + m.angular_acceleration.cross(l) + w.cross(w.cross(l))) + b_a_ +
            gauss3(na, na, na);
  r.gyro_bias = b_g_;
  r.accel_bias = b_a_;
  return r;
}

bool InertialSensorSimulator::in_outage(double t) const {
  if (gnss_.outage_period_s <= 0 || gnss_.outage_duration_s <= 0) return false;
  const double phase = std::fmod(t, gnss_.outage_period_s);
  return phase >= gnss_.outage_period_s - gnss_.outage_duration_s;
}

std::optional<GnssReading> InertialSensorSimulator::gnss(double t) {
  if (in_outage(t)) return std::nullopt;
  const Eigen::Isometry3d T = truth_(t);
  const TrueMotion m = true_motion(truth_, t, imu_.gravity);
  GnssReading r;
  r.t = t;
  r.true_enu = T.translation() + T.linear() * gnss_.lever_arm;
  r.true_velocity = m.velocity + T.linear() * m.angular_velocity.cross(gnss_.lever_arm);
  r.enu = r.true_enu + gauss3(gnss_.horizontal_sigma, gnss_.horizontal_sigma, gnss_.vertical_sigma);
  r.velocity = r.true_velocity + gauss3(gnss_.velocity_sigma, gnss_.velocity_sigma, gnss_.velocity_sigma);
  if (gnss_.outlier_probability > 0 && random::uniform01(rng_) < gnss_.outlier_probability) {
    r.outlier = true;
    r.enu += gauss3(gnss_.outlier_sigma, gnss_.outlier_sigma, 0);
  }
  r.fix = plane_.to_geodetic(r.enu);
  return r;
}

sextant::imu_t InertialSensorSimulator::to_message(const ImuReading& r, const SimulatedImuOptions& o, int64_t utime,
                                                   const std::string& source, int64_t seq) {
  sextant::imu_t m{};
  m.utime = utime;
  m.sender = "sextant-simulate";
  m.seq = seq;
  m.source = source;
  m.frame = "imu";
  m.has_angular_velocity = m.has_linear_acceleration = true;
  const double vg = o.noise.gyro_noise_density * o.noise.gyro_noise_density * o.rate_hz;
  const double va = o.noise.accel_noise_density * o.noise.accel_noise_density * o.rate_hz;
  for (int i = 0; i < 3; ++i) {
    m.angular_velocity[i] = r.gyro[i];
    m.linear_acceleration[i] = r.accel[i];
    m.angular_velocity_covariance[4 * i] = vg;
    m.linear_acceleration_covariance[4 * i] = va;
  }
  m.orientation[0] = 1;
  return m;
}

sextant::gnss_t InertialSensorSimulator::to_message(const GnssReading& r, const SimulatedGnssOptions& o, int64_t utime,
                                                    const std::string& source, int64_t seq) {
  sextant::gnss_t m{};
  m.utime = utime;
  m.sender = "sextant-simulate";
  m.seq = seq;
  m.source = source;
  m.frame = "gnss";
  m.status = sextant::gnss_t::STATUS_FIX;
  m.latitude = r.fix.latitude, m.longitude = r.fix.longitude, m.altitude = r.fix.altitude;
  m.covariance_type = sextant::gnss_t::COVARIANCE_DIAGONAL_KNOWN;
  m.position_covariance[0] = m.position_covariance[4] = o.horizontal_sigma * o.horizontal_sigma;
  m.position_covariance[8] = o.vertical_sigma * o.vertical_sigma;
  m.has_velocity = true;
  for (int i = 0; i < 3; ++i) {
    m.velocity[i] = r.velocity[i];
    m.velocity_covariance[4 * i] = o.velocity_sigma * o.velocity_sigma;
  }
  return m;
}

}  // namespace sextant::tools
