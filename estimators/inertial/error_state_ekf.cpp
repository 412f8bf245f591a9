#include "estimators/inertial/error_state_ekf.hpp"

#include "estimators/lie/so3.hpp"

#include <algorithm>
#include <cmath>

namespace sextant::inertial {
namespace {

using Matrix3x15 = ErrorStateEkf::Matrix3x15;
constexpr int kP = ErrorStateEkf::kP, kV = ErrorStateEkf::kV, kTheta = ErrorStateEkf::kTheta;
constexpr int kBa = ErrorStateEkf::kBa, kBg = ErrorStateEkf::kBg;

double wrap_angle(double a) { return std::remainder(a, 2 * M_PI); }

}  // namespace

const char* imu_result_name(ImuResult r) {
  switch (r) {
    case ImuResult::propagated:
      return "propagated";
    case ImuResult::started:
      return "started";
    case ImuResult::gap:
      return "gap";
    case ImuResult::out_of_order:
      return "out_of_order";
    case ImuResult::non_finite:
      return "non_finite";
    case ImuResult::not_initialized:
      return "not_initialized";
  }
  return "unknown";
}

void ErrorStateEkf::initialize(double t, const EskfState& x, const Matrix15& P) {
  t_ = t;
  x_ = x;
  x_.q.normalize();
  P_ = P;
  initialized_ = true;
  has_sample_ = false;
}

EskfState ErrorStateEkf::step(const EskfState& x, const BodyImuSample& s, double dt, const Eigen::Vector3d& gravity,
                              Matrix15* F) {
  const Eigen::Vector3d w = s.gyro - x.b_g;
  const Eigen::Vector3d am = s.accel - x.b_a;
  const Eigen::Matrix3d R = x.q.toRotationMatrix();
  const Eigen::Vector3d a = R * am + gravity;
  Eigen::Matrix3d Jr;
  const SO3 dq = SO3::exp(w * dt, F ? &Jr : nullptr);
  EskfState y = x;
  y.p = x.p + x.v * dt + 0.5 * a * dt * dt;
  y.v = x.v + a * dt;
  y.q = (x.q * dq.quaternion()).normalized();
  if (F) {
    const Eigen::Matrix3d R_am = R * SO3::hat(am);
    F->setIdentity();
    F->block<3, 3>(kP, kV) = Eigen::Matrix3d::Identity() * dt;
    F->block<3, 3>(kP, kTheta) = -0.5 * R_am * dt * dt;
    F->block<3, 3>(kP, kBa) = -0.5 * R * dt * dt;
    F->block<3, 3>(kV, kTheta) = -R_am * dt;
    F->block<3, 3>(kV, kBa) = -R * dt;
    F->block<3, 3>(kTheta, kTheta) = dq.matrix().transpose();
    F->block<3, 3>(kTheta, kBg) = -Jr * dt;
  }
  return y;
}

EskfState ErrorStateEkf::inject(const EskfState& x, const Vector15& dx) {
  EskfState y = x;
  y.p += dx.segment<3>(kP);
  y.v += dx.segment<3>(kV);
  y.q = (x.q * SO3::exp(dx.segment<3>(kTheta)).quaternion()).normalized();
  y.b_a += dx.segment<3>(kBa);
  y.b_g += dx.segment<3>(kBg);
  return y;
}

ErrorStateEkf::Vector15 ErrorStateEkf::difference(const EskfState& x_b, const EskfState& x_a) {
  Vector15 d;
  d.segment<3>(kP) = x_b.p - x_a.p;
  d.segment<3>(kV) = x_b.v - x_a.v;
  d.segment<3>(kTheta) = SO3(x_a.q.conjugate() * x_b.q).log();
  d.segment<3>(kBa) = x_b.b_a - x_a.b_a;
  d.segment<3>(kBg) = x_b.b_g - x_a.b_g;
  return d;
}

void ErrorStateEkf::propagate(double dt) {
  Matrix15 F;
  x_ = step(x_, held_, dt, options_.gravity, &F);
  P_ = F * P_ * F.transpose();
  // Q (eq. 271) from the densities: velocity and angle impulses, bias random walks.
  const ImuNoise& n = options_.noise;
  P_.diagonal().segment<3>(kV).array() += n.accel_noise_density * n.accel_noise_density * dt;
  P_.diagonal().segment<3>(kTheta).array() += n.gyro_noise_density * n.gyro_noise_density * dt;
  P_.diagonal().segment<3>(kBa).array() += n.accel_bias_random_walk * n.accel_bias_random_walk * dt;
  P_.diagonal().segment<3>(kBg).array() += n.gyro_bias_random_walk * n.gyro_bias_random_walk * dt;
  t_ += dt;
}

ImuResult ErrorStateEkf::add_imu(double t, const BodyImuSample& sample) {
  if (!initialized_) return ImuResult::not_initialized;
  if (!std::isfinite(t) || !sample.gyro.allFinite() || !sample.accel.allFinite()) return ImuResult::non_finite;
  if (t < t_) return ImuResult::out_of_order;
  ImuResult result = ImuResult::propagated;
  if (!has_sample_) {
    result = ImuResult::started;
  } else if (t - t_ > options_.max_dt) {
    result = ImuResult::gap;
  } else if (t > t_) {
    propagate(t - t_);
  }
  t_ = t;
  held_ = sample;
  has_sample_ = true;
  return result;
}

bool ErrorStateEkf::propagate_to(double t) {
  if (!initialized_ || !has_sample_ || !(t >= t_) || t - t_ > options_.max_dt) return false;
  if (t > t_) propagate(t - t_);
  return true;
}

filter::UpdateResult ErrorStateEkf::fuse(const Eigen::Vector3d& innovation, const Matrix3x15& H,
                                         const Eigen::Matrix3d& R, const FieldMask& fields, double gate) {
  int rows[3], m = 0;
  for (int i = 0; i < 3; ++i)
    if (fields[static_cast<size_t>(i)]) rows[m++] = i;
  filter::UpdateResult out;
  if (!initialized_ || m == 0) {
    out.reason = filter::UpdateReason::kNoComponents;
    return out;
  }
  Eigen::VectorXd r(m);
  Eigen::MatrixXd Hs(m, kDim), Rs(m, m);
  for (int i = 0; i < m; ++i) {
    r(i) = innovation(rows[i]);
    Hs.row(i) = H.row(rows[i]);
    for (int j = 0; j < m; ++j) Rs(i, j) = R(rows[i], rows[j]);
  }
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(kDim);
  Eigen::MatrixXd P = P_;
  out = filter::kalman_update(dx, P, r, Hs, Rs, gate);
  if (!out.accepted) return out;
  // Injection and reset (eqs. 283-287): the rotation error moves from the old to the new nominal rotation.
  x_ = inject(x_, dx);
  Matrix15 G = Matrix15::Identity();
  G.block<3, 3>(kTheta, kTheta) -= SO3::hat(0.5 * dx.segment<3>(kTheta));
  P_ = G * P * G.transpose();
  return out;
}

Eigen::Vector3d ErrorStateEkf::roll_pitch_yaw(const Eigen::Matrix3d& R) {
  return {std::atan2(R(2, 1), R(2, 2)), std::asin(std::clamp(-R(2, 0), -1.0, 1.0)), std::atan2(R(1, 0), R(0, 0))};
}

Eigen::Vector3d ErrorStateEkf::body_velocity_model(const EskfState& x, const Eigen::Vector3d& gyro,
                                                   const SensorMounting& m, Matrix3x15* H) {
  const Eigen::Matrix3d R = x.q.toRotationMatrix();
  const Eigen::Vector3d v_body = R.transpose() * x.v;
  const Eigen::Vector3d w = gyro - x.b_g;
  const Eigen::Matrix3d Rsb = m.rotation.transpose();
  if (H) {
    H->setZero();
    H->block<3, 3>(0, kV) = Rsb * R.transpose();
    H->block<3, 3>(0, kTheta) = Rsb * SO3::hat(v_body);
    H->block<3, 3>(0, kBg) = Rsb * SO3::hat(m.lever_arm);
  }
  return Rsb * (v_body + w.cross(m.lever_arm));
}

Eigen::Vector3d ErrorStateEkf::euler_model(const EskfState& x, Matrix3x15* H) {
  const Eigen::Vector3d rpy = roll_pitch_yaw(x.q.toRotationMatrix());
  if (H) {
    // d[roll, pitch, yaw] / d(body-frame rotation): the inverse of the Z-Y-X Euler rate matrix.
    const double sr = std::sin(rpy(0)), cr = std::cos(rpy(0)), cp = std::cos(rpy(1)), tp = std::tan(rpy(1));
    H->setZero();
    H->block<3, 3>(0, kTheta) << 1, sr * tp, cr * tp, 0, cr, -sr, 0, sr / cp, cr / cp;
  }
  return rpy;
}

Eigen::Vector3d ErrorStateEkf::gnss_position_model(const EskfState& x, const Eigen::Vector3d& lever, Matrix3x15* H) {
  const Eigen::Matrix3d R = x.q.toRotationMatrix();
  if (H) {
    H->setZero();
    H->block<3, 3>(0, kP).setIdentity();
    H->block<3, 3>(0, kTheta) = -R * SO3::hat(lever);
  }
  return x.p + R * lever;
}

Eigen::Vector3d ErrorStateEkf::gnss_velocity_model(const EskfState& x, const Eigen::Vector3d& gyro,
                                                   const Eigen::Vector3d& lever, Matrix3x15* H) {
  const Eigen::Matrix3d R = x.q.toRotationMatrix();
  const Eigen::Vector3d w_x_t = (gyro - x.b_g).cross(lever);
  if (H) {
    H->setZero();
    H->block<3, 3>(0, kV).setIdentity();
    H->block<3, 3>(0, kTheta) = -R * SO3::hat(w_x_t);
    H->block<3, 3>(0, kBg) = R * SO3::hat(lever);
  }
  return x.v + R * w_x_t;
}

filter::UpdateResult ErrorStateEkf::update_body_velocity(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                                         const SensorMounting& m, const FieldMask& fields,
                                                         double gate) {
  Matrix3x15 H;
  const Eigen::Vector3d h = body_velocity_model(x_, held_.gyro, m, &H);
  return fuse(z - h, H, R, fields, gate);
}

filter::UpdateResult ErrorStateEkf::update_orientation(const Eigen::Quaterniond& q_ws, const Eigen::Matrix3d& R,
                                                       const SensorMounting& m, const FieldMask& fields, double gate) {
  if (!q_ws.coeffs().allFinite() || q_ws.norm() < 1e-6) {
    filter::UpdateResult out;
    out.reason = filter::UpdateReason::kNonFinite;
    return out;
  }
  Matrix3x15 H;
  const Eigen::Vector3d h = euler_model(x_, &H);
  const Eigen::Vector3d z = roll_pitch_yaw(q_ws.normalized().toRotationMatrix() * m.rotation.transpose());
  const Eigen::Vector3d r(wrap_angle(z(0) - h(0)), wrap_angle(z(1) - h(1)), wrap_angle(z(2) - h(2)));
  return fuse(r, H, R, fields, gate);
}

filter::UpdateResult ErrorStateEkf::update_gnss_position(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                                         const Eigen::Vector3d& lever, const FieldMask& fields,
                                                         double gate) {
  Matrix3x15 H;
  const Eigen::Vector3d h = gnss_position_model(x_, lever, &H);
  return fuse(z - h, H, R, fields, gate);
}

filter::UpdateResult ErrorStateEkf::update_gnss_velocity(const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                                                         const Eigen::Vector3d& lever, const FieldMask& fields,
                                                         double gate) {
  Matrix3x15 H;
  const Eigen::Vector3d h = gnss_velocity_model(x_, held_.gyro, lever, &H);
  return fuse(z - h, H, R, fields, gate);
}

}  // namespace sextant::inertial
