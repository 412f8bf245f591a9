#pragma once
// Factors of an inertial keyframe graph (estimators/graph/factor.hpp's conventions: residual e, information Omega,
// Jacobians with respect to each variable's right perturbation).
//
// A keyframe k has four variables: its pose X_k = (R_k, p_k) (graph::VariableKind::kPose3, body to world, tangent
// [rho; phi]: p <- p + R rho, R <- R Exp(phi) to first order), its velocity v_k (kVector3, m/s, world frame) and the
// IMU's gyroscope and accelerometer biases b_g,k (rad/s) and b_a,k (m/s^2) (kVector3 each, body frame).  The world
// frame has z up; gravity g = [0, 0, -9.80665] m/s^2 unless told otherwise.
#include "estimators/graph/factor.hpp"
#include "estimators/graph/robust_kernel.hpp"
#include "estimators/inertial/imu_preintegration.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace sextant::inertial {

/// The variables of one keyframe, as indices into the graph's variables.
struct KeyframeVariables {
  int pose = -1, velocity = -1, gyro_bias = -1, accel_bias = -1;
};

/// The navigation state and bias of keyframe `k` read from the graph's variables.
NavState nav_state(const std::vector<graph::Variable>& vars, const KeyframeVariables& k);
ImuBias imu_bias(const std::vector<graph::Variable>& vars, const KeyframeVariables& k);

/// The preintegrated IMU between keyframes i and j (Forster et al. TRO 2017, eq. 45), on the variables
/// {X_i, v_i, b_g,i, b_a,i, X_j, v_j}: the residual of ImuPreintegration::residual [r_R, r_v, r_p], the
/// preintegrated deltas corrected to first order for the bias at i, with information the inverse of the
/// preintegration's covariance.
class ImuFactor final : public graph::Factor {
 public:
  /// Throws std::invalid_argument when the preintegration is empty or its covariance is not positive definite.
  ImuFactor(const KeyframeVariables& i, const KeyframeVariables& j, ImuPreintegration preintegration,
            const Eigen::Vector3d& gravity);
  std::unique_ptr<graph::Factor> clone() const override { return std::make_unique<ImuFactor>(*this); }
  std::string type() const override { return "IMU_PREINTEGRATED"; }
  void error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const override;
  const ImuPreintegration& preintegration() const { return pim_; }

 private:
  ImuPreintegration pim_;
  Eigen::Vector3d gravity_;
};

/// A random walk of a 3-vector between two keyframes (an IMU bias): e = b_j - b_i, covariance density^2 dt I
/// (density in the bias's unit per sqrt(s), e.g. rad/s^2/sqrt(Hz) for a gyroscope bias).
class RandomWalkFactor final : public graph::Factor {
 public:
  /// Throws std::invalid_argument for a density or dt that is not positive and finite.
  RandomWalkFactor(int i, int j, double density, double dt);
  std::unique_ptr<graph::Factor> clone() const override { return std::make_unique<RandomWalkFactor>(*this); }
  std::string type() const override { return "RANDOM_WALK"; }
  void error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const override;
};

/// A GNSS antenna position z (world frame, ENU metres, covariance S) at time t_i + tau, on keyframe i: the antenna
/// sits at lever arm l in the body frame, and the motion since the keyframe comes from the IMU preintegrated over
/// [t_i, t_i + tau] (empty for a fix at the keyframe's time):
///   p(t) = p_i + v_i tau + g tau^2 / 2 + R_i dp(b),  R(t) = R_i dR(b)          (eq. 38 at time t)
///   u = L^T (p(t) + R(t) l - z),  S^-1 = L L^T                                   (whitened residual)
///   e = c(s) u,  s = u'u,  c(s) = sqrt(rho(s) / s)                                 (robust)
/// so that e'e = rho(s), the robust cost itself (robust_kernel.hpp's rho, kernel kNone: e = u); the Jacobians are
/// exact, c's derivative included.  Variables {X_i, v_i, b_g,i, b_a,i} with a preintegration, {X_i} without;
/// information I (3 x 3).  A multipath fix tens of sigmas off then pulls with the kernel's bounded influence.
class GnssPositionFactor final : public graph::Factor {
 public:
  /// A fix at the keyframe's own time.  Throws std::invalid_argument when S is not positive definite, a value is not
  /// finite or the kernel's width is not positive.
  GnssPositionFactor(int pose, const Eigen::Vector3d& z, const Eigen::Matrix3d& covariance,
                     const Eigen::Vector3d& lever_arm, graph::RobustKernel kernel, double kernel_width);
  /// A fix `since_keyframe.dt()` seconds after keyframe k.
  GnssPositionFactor(const KeyframeVariables& k, const ImuPreintegration& since_keyframe,
                     const Eigen::Vector3d& gravity, const Eigen::Vector3d& z, const Eigen::Matrix3d& covariance,
                     const Eigen::Vector3d& lever_arm, graph::RobustKernel kernel, double kernel_width);
  std::unique_ptr<graph::Factor> clone() const override { return std::make_unique<GnssPositionFactor>(*this); }
  std::string type() const override { return "GNSS_POSITION"; }
  bool fixes_gauge() const override { return true; }
  void error(const std::vector<graph::Variable>& vars, Eigen::VectorXd& e) const override;
  void linearize(const std::vector<graph::Variable>& vars, graph::Linearization& out) const override;
  /// The squared whitened error s = u'u (before the kernel): a chi-square(3) variable for a good fix.
  double squared_error(const std::vector<graph::Variable>& vars) const;
  /// The antenna's predicted position p(t) + R(t) l (world frame).
  Eigen::Vector3d predicted(const std::vector<graph::Variable>& vars) const;

 private:
  void check() const;
  /// The antenna position and, when asked, its derivatives with respect to each variable (3 x dim).
  Eigen::Vector3d antenna(const std::vector<graph::Variable>& vars, std::vector<Eigen::MatrixXd>* J) const;
  bool with_imu_;
  ImuPreintegration pim_;
  Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero(), z_, lever_;
  Eigen::Matrix3d whiten_;  // L^T
  graph::RobustKernel kernel_;
  double width_;
};

}  // namespace sextant::inertial
