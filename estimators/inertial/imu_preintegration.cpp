#include "estimators/inertial/imu_preintegration.hpp"

#include "estimators/lie/so3.hpp"

#include <cmath>
#include <stdexcept>

namespace sextant::inertial {

ImuPreintegration::ImuPreintegration(const ImuBias& bias, const ImuNoise& noise) : bias_(bias), noise_(noise) {}

void ImuPreintegration::reset(const ImuBias& bias) { *this = ImuPreintegration(bias, noise_); }

void ImuPreintegration::transition(const Eigen::Matrix3d& dR, const Eigen::Matrix3d& dR_step, const Eigen::Vector3d& a,
                                   double dt, Matrix9& A) {
  const Eigen::Matrix3d dR_ax = dR * SO3::hat(a);
  A.setIdentity();
  A.block<3, 3>(0, 0) = dR_step.transpose();
  A.block<3, 3>(3, 0) = -dR_ax * dt;
  A.block<3, 3>(6, 0) = -0.5 * dR_ax * dt * dt;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt;
}

void ImuPreintegration::error_propagation(const Eigen::Matrix3d& dR, const Eigen::Vector3d& w, const Eigen::Vector3d& a,
                                          double dt, Matrix9* A, Matrix93* B, Matrix93* C) {
  Eigen::Matrix3d Jr;
  const Eigen::Matrix3d dR_step = SO3::exp(w * dt, &Jr).matrix();
  if (A) transition(dR, dR_step, a, dt, *A);
  if (B) {
    B->setZero();
    B->block<3, 3>(0, 0) = Jr * dt;
  }
  if (C) {
    C->setZero();
    C->block<3, 3>(3, 0) = dR * dt;
    C->block<3, 3>(6, 0) = 0.5 * dR * dt * dt;
  }
}

void ImuPreintegration::propagate_jacobians(const Eigen::Matrix3d& dR_step, const Eigen::Matrix3d& Jr,
                                            const Eigen::Vector3d& a, double dt) {
  // Appendix B, in the order that uses the values before this sample (dR_, dR_dbg_, dv_*) on the right.
  const Eigen::Matrix3d dR_ax = dR_ * SO3::hat(a);
  const double dt2 = dt * dt;
  dp_dba_ += dv_dba_ * dt - 0.5 * dR_ * dt2;
  dp_dbg_ += dv_dbg_ * dt - 0.5 * dR_ax * dR_dbg_ * dt2;
  dv_dba_ -= dR_ * dt;
  dv_dbg_ -= dR_ax * dR_dbg_ * dt;
  dR_dbg_ = dR_step.transpose() * dR_dbg_ - Jr * dt;
}

void ImuPreintegration::integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw std::invalid_argument("imu preintegration: dt must be positive and finite");
  if (!gyro.allFinite() || !accel.allFinite())
    throw std::invalid_argument("imu preintegration: non-finite gyroscope or accelerometer sample");
  const Eigen::Vector3d w = gyro - bias_.gyro;
  const Eigen::Vector3d a = accel - bias_.accel;
  Eigen::Matrix3d Jr;
  const Eigen::Matrix3d dR_step = SO3::exp(w * dt, &Jr).matrix();

  // Covariance (eq. 63): the noise terms B Sigma_g B^T = sg^2 dt Jr Jr^T and C Sigma_a C^T = sa^2 dt [dR; dR dt/2]
  // [dR; dR dt/2]^T, with the discrete variances density^2 / dt.
  Matrix9 A;
  transition(dR_, dR_step, a, dt, A);
  cov_ = A * cov_ * A.transpose();
  const double qg = noise_.gyro_noise_density * noise_.gyro_noise_density * dt;
  const double qa = noise_.accel_noise_density * noise_.accel_noise_density * dt;
  cov_.block<3, 3>(0, 0).noalias() += qg * Jr * Jr.transpose();
  cov_.block<3, 3>(3, 3) += qa * Eigen::Matrix3d::Identity();  // dR dR^T = I
  cov_.block<3, 3>(3, 6) += 0.5 * dt * qa * Eigen::Matrix3d::Identity();
  cov_.block<3, 3>(6, 3) += 0.5 * dt * qa * Eigen::Matrix3d::Identity();
  cov_.block<3, 3>(6, 6) += 0.25 * dt * dt * qa * Eigen::Matrix3d::Identity();

  propagate_jacobians(dR_step, Jr, a, dt);

  // The deltas (eq. 33), position first: it uses the velocity and rotation before this sample.
  const Eigen::Vector3d dR_a = dR_ * a;
  dp_ += dv_ * dt + 0.5 * dR_a * dt * dt;
  dv_ += dR_a * dt;
  dR_ = dR_ * dR_step;
  dt_ += dt;
}

Eigen::Matrix3d ImuPreintegration::corrected_delta_R(const ImuBias& b) const {
  return dR_ * SO3::exp(dR_dbg_ * (b.gyro - bias_.gyro)).matrix();
}

Eigen::Vector3d ImuPreintegration::corrected_delta_v(const ImuBias& b) const {
  return dv_ + dv_dbg_ * (b.gyro - bias_.gyro) + dv_dba_ * (b.accel - bias_.accel);
}

Eigen::Vector3d ImuPreintegration::corrected_delta_p(const ImuBias& b) const {
  return dp_ + dp_dbg_ * (b.gyro - bias_.gyro) + dp_dba_ * (b.accel - bias_.accel);
}

NavState ImuPreintegration::predict(const NavState& i, const ImuBias& b, const Eigen::Vector3d& g) const {
  NavState j;
  j.R = i.R * corrected_delta_R(b);
  j.v = i.v + g * dt_ + i.R * corrected_delta_v(b);
  j.p = i.p + i.v * dt_ + 0.5 * g * dt_ * dt_ + i.R * corrected_delta_p(b);
  return j;
}

ImuPreintegration::Vector9 ImuPreintegration::residual(const NavState& i, const NavState& j, const ImuBias& b,
                                                       const Eigen::Vector3d& g, Matrix9x15* J_i, Matrix9* J_j) const {
  const Eigen::Vector3d dbg = b.gyro - bias_.gyro;
  const Eigen::Matrix3d dR_b = corrected_delta_R(b);
  const Eigen::Matrix3d Rit = i.R.transpose();
  const Eigen::Vector3d dv_world = Rit * (j.v - i.v - g * dt_);
  const Eigen::Vector3d dp_world = Rit * (j.p - i.p - i.v * dt_ - 0.5 * g * dt_ * dt_);
  Eigen::Matrix3d Jr_inv;
  Vector9 r;
  r.segment<3>(0) = SO3(Eigen::Matrix3d(dR_b.transpose() * Rit * j.R)).log(&Jr_inv);
  r.segment<3>(3) = dv_world - corrected_delta_v(b);
  r.segment<3>(6) = dp_world - corrected_delta_p(b);
  // Error-state offsets of the filter: [dp, dv, dth, db_a, db_g].
  constexpr int P = 0, V = 3, TH = 6, BA = 9, BG = 12;
  if (J_i) {
    J_i->setZero();
    const Eigen::Matrix3d E = SO3::exp(r.segment<3>(0)).matrix();
    J_i->block<3, 3>(0, TH) = -Jr_inv * j.R.transpose() * i.R;
    J_i->block<3, 3>(0, BG) = -Jr_inv * E.transpose() * SO3::right_jacobian(dR_dbg_ * dbg) * dR_dbg_;
    J_i->block<3, 3>(3, V) = -Rit;
    J_i->block<3, 3>(3, TH) = SO3::hat(dv_world);
    J_i->block<3, 3>(3, BA) = -dv_dba_;
    J_i->block<3, 3>(3, BG) = -dv_dbg_;
    J_i->block<3, 3>(6, P) = -Rit;
    J_i->block<3, 3>(6, V) = -Rit * dt_;
    J_i->block<3, 3>(6, TH) = SO3::hat(dp_world);
    J_i->block<3, 3>(6, BA) = -dp_dba_;
    J_i->block<3, 3>(6, BG) = -dp_dbg_;
  }
  if (J_j) {
    J_j->setZero();
    J_j->block<3, 3>(0, TH) = Jr_inv;
    J_j->block<3, 3>(3, V) = Rit;
    J_j->block<3, 3>(6, P) = Rit;
  }
  return r;
}

}  // namespace sextant::inertial
