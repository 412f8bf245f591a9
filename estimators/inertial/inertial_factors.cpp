#include "estimators/inertial/inertial_factors.hpp"

#include "estimators/lie/so3.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Cholesky>

#include <cmath>
#include <stdexcept>

namespace sextant::inertial {
namespace {

const graph::Variable& at(const std::vector<graph::Variable>& vars, int index) {
  return vars[static_cast<size_t>(index)];
}

// Offsets of the filter's error state in ImuPreintegration::residual's Jacobians: [dp, dv, dth, db_a, db_g].
constexpr int kP = 0, kV = 3, kTh = 6, kBa = 9, kBg = 12;

Eigen::MatrixXd preintegrated_information(const ImuPreintegration& pim) {
  if (!(pim.dt() > 0))
    throw std::invalid_argument("ImuFactor: an empty preintegration (no IMU sample between keyframes)");
  if (!is_positive_definite(pim.covariance()))
    throw std::invalid_argument("ImuFactor: the preintegrated covariance is not positive definite");
  return symmetrized(pim.covariance().inverse());
}

Eigen::MatrixXd random_walk_information(double density, double dt) {
  if (!(density > 0) || !std::isfinite(density) || !(dt > 0) || !std::isfinite(dt))
    throw std::invalid_argument("RandomWalkFactor: the density and dt must be positive and finite");
  return Eigen::Matrix3d::Identity() / (density * density * dt);
}

// L^T with L L^T = covariance^-1.
Eigen::Matrix3d whitening(const Eigen::Matrix3d& covariance) {
  if (!is_positive_definite(covariance))
    throw std::invalid_argument("GnssPositionFactor: the fix's covariance is not positive definite");
  return Eigen::LLT<Eigen::Matrix3d>(covariance.inverse()).matrixL().transpose();
}

}  // namespace

NavState nav_state(const std::vector<graph::Variable>& vars, const KeyframeVariables& k) {
  const SE3& X = at(vars, k.pose).pose3;
  NavState s;
  s.R = X.rotation().matrix();
  s.p = X.translation();
  s.v = at(vars, k.velocity).point;
  return s;
}

ImuBias imu_bias(const std::vector<graph::Variable>& vars, const KeyframeVariables& k) {
  ImuBias b;
  b.gyro = at(vars, k.gyro_bias).point;
  b.accel = at(vars, k.accel_bias).point;
  return b;
}

ImuFactor::ImuFactor(const KeyframeVariables& i, const KeyframeVariables& j, ImuPreintegration preintegration,
                     const Eigen::Vector3d& gravity)
    : graph::Factor({i.pose, i.velocity, i.gyro_bias, i.accel_bias, j.pose, j.velocity},
                    preintegrated_information(preintegration)),
      pim_(std::move(preintegration)),
      gravity_(gravity) {}

void ImuFactor::error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const {
  const auto& v = variables();
  const KeyframeVariables i{v[0], v[1], v[2], v[3]}, j{v[4], v[5], -1, -1};
  e = pim_.residual(nav_state(vars, i), nav_state(vars, j), imu_bias(vars, i), gravity_);
}

void ImuFactor::linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const {
  const auto& v = variables();
  const KeyframeVariables i{v[0], v[1], v[2], v[3]}, j{v[4], v[5], -1, -1};
  const NavState si = nav_state(vars, i), sj = nav_state(vars, j);
  ImuPreintegration::Matrix9x15 Ji;
  ImuPreintegration::Matrix9 Jj;
  out.error = pim_.residual(si, sj, imu_bias(vars, i), gravity_, &Ji, &Jj);
  // The filter's world-frame position error dp against the pose's body-frame rho: dp = R rho.
  out.jacobians[0].resize(9, 6);
  out.jacobians[0] << Ji.middleCols<3>(kP) * si.R, Ji.middleCols<3>(kTh);
  out.jacobians[1] = Ji.middleCols<3>(kV);
  out.jacobians[2] = Ji.middleCols<3>(kBg);
  out.jacobians[3] = Ji.middleCols<3>(kBa);
  out.jacobians[4].resize(9, 6);
  out.jacobians[4] << Jj.middleCols<3>(kP) * sj.R, Jj.middleCols<3>(kTh);
  out.jacobians[5] = Jj.middleCols<3>(kV);
}

RandomWalkFactor::RandomWalkFactor(int i, int j, double density, double dt)
    : graph::Factor({i, j}, random_walk_information(density, dt)) {}

void RandomWalkFactor::error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const {
  e = at(vars, variables()[1]).point - at(vars, variables()[0]).point;
}

void RandomWalkFactor::linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const {
  error(vars, out.error);
  out.jacobians[0] = -Eigen::Matrix3d::Identity();
  out.jacobians[1] = Eigen::Matrix3d::Identity();
}

GnssPositionFactor::GnssPositionFactor(int pose, const Eigen::Vector3d& z, const Eigen::Matrix3d& covariance,
                                       const Eigen::Vector3d& lever_arm, graph::RobustKernel kernel,
                                       double kernel_width)
    : graph::Factor({pose}, Eigen::Matrix3d::Identity()),
      with_imu_(false),
      z_(z),
      lever_(lever_arm),
      whiten_(whitening(covariance)),
      kernel_(kernel),
      width_(kernel_width) {
  check();
}

GnssPositionFactor::GnssPositionFactor(const KeyframeVariables& k, const ImuPreintegration& since_keyframe,
                                       const Eigen::Vector3d& gravity, const Eigen::Vector3d& z,
                                       const Eigen::Matrix3d& covariance, const Eigen::Vector3d& lever_arm,
                                       graph::RobustKernel kernel, double kernel_width)
    : graph::Factor({k.pose, k.velocity, k.gyro_bias, k.accel_bias}, Eigen::Matrix3d::Identity()),
      with_imu_(true),
      pim_(since_keyframe),
      gravity_(gravity),
      z_(z),
      lever_(lever_arm),
      whiten_(whitening(covariance)),
      kernel_(kernel),
      width_(kernel_width) {
  check();
}

void GnssPositionFactor::check() const {
  if (!z_.allFinite() || !lever_.allFinite() || !gravity_.allFinite())
    throw std::invalid_argument("GnssPositionFactor: a non-finite fix, lever arm or gravity");
  if (kernel_ != graph::RobustKernel::kNone && (!(width_ > 0) || !std::isfinite(width_)))
    throw std::invalid_argument("GnssPositionFactor: the kernel's width must be positive and finite");
}

Eigen::Vector3d GnssPositionFactor::antenna(const std::vector<graph::Variable>& vars,
                                            std::vector<Eigen::MatrixXd>* J) const {
  const SE3& X = at(vars, variables()[0]).pose3;
  const Eigen::Matrix3d Ri = X.rotation().matrix();
  if (!with_imu_) {
    if (J) {
      (*J)[0].resize(3, 6);
      (*J)[0] << Ri, -Ri * SO3::hat(lever_);
    }
    return X.translation() + Ri * lever_;
  }
  const KeyframeVariables k{variables()[0], variables()[1], variables()[2], variables()[3]};
  const ImuBias b = imu_bias(vars, k);
  const Eigen::Vector3d vi = at(vars, k.velocity).point;
  const double tau = pim_.dt();
  const Eigen::Vector3d dbg = b.gyro - pim_.bias().gyro;
  const Eigen::Matrix3d dR = pim_.corrected_delta_R(b);
  const Eigen::Vector3d dp = pim_.corrected_delta_p(b);
  const Eigen::Vector3d arm = dR * lever_;
  if (J) {
    (*J)[0].resize(3, 6);
    (*J)[0] << Ri, -Ri * SO3::hat(dp + arm);
    (*J)[1] = tau * Eigen::Matrix3d::Identity();
    // d(dR(b) l)/d b_g = -dR(b) [l]x Jr(A dbg) A, A = d dR / d b_g (the first-order bias correction of eq. 44).
    (*J)[2] = Ri * (pim_.dp_dbg() - dR * SO3::hat(lever_) * SO3::right_jacobian(pim_.dR_dbg() * dbg) * pim_.dR_dbg());
    (*J)[3] = Ri * pim_.dp_dba();
  }
  return X.translation() + vi * tau + 0.5 * gravity_ * tau * tau + Ri * (dp + arm);
}

Eigen::Vector3d GnssPositionFactor::predicted(const std::vector<graph::Variable>& vars) const {
  return antenna(vars, nullptr);
}

double GnssPositionFactor::squared_error(const std::vector<graph::Variable>& vars) const {
  return (whiten_ * (antenna(vars, nullptr) - z_)).squaredNorm();
}

void GnssPositionFactor::error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const {
  const Eigen::Vector3d u = whiten_ * (antenna(vars, nullptr) - z_);
  const double s = u.squaredNorm();
  e = s > 0 ? Eigen::Vector3d(u * std::sqrt(graph::robust_cost(kernel_, width_, s) / s)) : u;
}

void GnssPositionFactor::linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const {
  const Eigen::Vector3d u = whiten_ * (antenna(vars, &out.jacobians) - z_);
  const double s = u.squaredNorm();
  // e = c(s) u with c = sqrt(rho / s): de/dx = (c I + 2 c'(s) u u') du/dx, c' = (rho' s - rho) / (2 s^2 c).
  Eigen::Matrix3d D = whiten_;
  out.error = u;
  if (s > 1e-300 && kernel_ != graph::RobustKernel::kNone) {
    const double rho = graph::robust_cost(kernel_, width_, s), c = std::sqrt(rho / s);
    const double dc = (graph::robust_weight(kernel_, width_, s) * s - rho) / (2 * s * s * c);
    D = (c * Eigen::Matrix3d::Identity() + 2 * dc * u * u.transpose()) * whiten_;
    out.error = c * u;
  }
  for (auto& J : out.jacobians) J = D * J;
}

}  // namespace sextant::inertial
