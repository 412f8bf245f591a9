#pragma once
// IMU preintegration on the manifold (Forster, Carlone, Dellaert, Scaramuzza, "On-manifold preintegration for real-time
// visual-inertial odometry", IEEE TRO 2017; equation numbers below are that paper's).
//
// Between two times i and j the IMU samples (gyroscope w~_k, accelerometer specific force a~_k, held constant over
// [t_k, t_k + dt_k]) are summarised, independently of the states at i and j, as
//   dR_ij = prod_k Exp((w~_k - b_g) dt_k)                                   (eq. 33)
//   dv_ij = sum_k dR_ik (a~_k - b_a) dt_k
//   dp_ij = sum_k dv_ik dt_k + 1/2 dR_ik (a~_k - b_a) dt_k^2
// at a fixed bias estimate (b_g, b_a) = the linearisation point.  The states then satisfy, with gravity g in the world
// frame (z up: g = [0, 0, -9.81]):
//   R_j = R_i dR_ij,   v_j = v_i + g dt_ij + R_i dv_ij,   p_j = p_i + v_i dt_ij + 1/2 g dt_ij^2 + R_i dp_ij   (eq. 38)
// exactly for piecewise-constant samples.
//
// Noise: the preintegrated error [d_phi, d_v, d_p] of the quantities integrated from noisy samples (dR~ = dR Exp(d_phi),
// dv~ = dv + d_v, dp~ = dp + d_p, eq. 42, with w~ = w + b_g + eta_g and a~ = a + b_a + eta_a) is
// propagated sample by sample as Sigma <- A Sigma A^T + B Sigma_g B^T + C Sigma_a C^T (eqs. 62-63, Appendix A) from
// the white-noise densities of the gyroscope and accelerometer (discrete variances density^2 / dt).
// Bias: a change db of the bias from the linearisation point is applied to first order (eq. 44):
//   dR(b) = dR Exp(dR/db_g db_g),  dv(b) = dv + dv/db_g db_g + dv/db_a db_a,  dp(b) likewise,
// with the Jacobians accumulated sample by sample (Appendix B).  Re-integrate when |db| grows large.
// Frames: samples and biases in the IMU (body) frame; the covariance is ordered [rotation, velocity, position]
// (Forster's order, rad and m/s and m).
#include <Eigen/Core>

namespace sextant::inertial {

/// The continuous-time white-noise densities of an IMU (a data sheet's or Kalibr's "noise density").
struct ImuNoise {
  double gyro_noise_density = 1.7e-4;      // rad/s/sqrt(Hz) (EuRoC's ADIS16448)
  double accel_noise_density = 2.0e-3;     // m/s^2/sqrt(Hz)
  double gyro_bias_random_walk = 1.9e-5;   // rad/s^2/sqrt(Hz)
  double accel_bias_random_walk = 3.0e-3;  // m/s^3/sqrt(Hz)
};

/// The bias of an IMU in its own frame.
struct ImuBias {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  // m/s^2
};

/// A navigation state: body-to-world rotation, velocity and position of the body origin in the world frame.
struct NavState {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d p = Eigen::Vector3d::Zero();  // m
};

class ImuPreintegration {
 public:
  using Matrix9 = Eigen::Matrix<double, 9, 9>;
  using Matrix93 = Eigen::Matrix<double, 9, 3>;

  /// Preintegration at the bias linearisation point `bias`.
  explicit ImuPreintegration(const ImuBias& bias = {}, const ImuNoise& noise = {});

  /// Starts over (empty interval) at a new bias linearisation point.
  void reset(const ImuBias& bias);
  /// Adds one sample held for `dt` seconds (> 0; a non-finite or non-positive dt, or a non-finite sample, throws
  /// std::invalid_argument).  `gyro` rad/s, `accel` specific force m/s^2, both in the IMU frame.
  void integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt);

  double dt() const { return dt_; }  // seconds integrated
  const Eigen::Matrix3d& delta_R() const { return dR_; }
  const Eigen::Vector3d& delta_v() const { return dv_; }
  const Eigen::Vector3d& delta_p() const { return dp_; }
  const ImuBias& bias() const { return bias_; }
  /// Covariance of [d_phi, d_v, d_p] (eq. 63).
  const Matrix9& covariance() const { return cov_; }

  // Jacobians of the preintegrated quantities with respect to the biases at the linearisation point (Appendix B):
  // dR(b_g + db) ~ dR Exp(dR_dbg db), dv(b + db) ~ dv + dv_dbg db_g + dv_dba db_a, dp likewise.
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }

  /// The preintegrated quantities at another bias, to first order (eq. 44).
  Eigen::Matrix3d corrected_delta_R(const ImuBias& b) const;
  Eigen::Vector3d corrected_delta_v(const ImuBias& b) const;
  Eigen::Vector3d corrected_delta_p(const ImuBias& b) const;

  /// The state at j from the state at i (eq. 38) at bias `b` (first-order corrected), gravity `g` in the world frame.
  NavState predict(const NavState& i, const ImuBias& b, const Eigen::Vector3d& g) const;

  /// The residual of a preintegrated-IMU factor between the states i and j with the bias b at i (eq. 45), ordered
  /// like covariance() [r_R, r_v, r_p]:
  ///   r_R = Log(dR(b)^T R_i^T R_j),  r_v = R_i^T (v_j - v_i - g dt) - dv(b),
  ///   r_p = R_i^T (p_j - p_i - v_i dt - g dt^2 / 2) - dp(b)
  /// with the first-order corrected deltas.  Jacobians (when asked) with respect to the error states of the
  /// error-state filter (error_state_ekf.hpp): J_i over [dp_i, dv_i, dth_i, db_a, db_g] (9 x 15) and J_j over
  /// [dp_j, dv_j, dth_j] (9 x 9), where p <- p + dp, v <- v + dv, R <- R Exp(dth), b <- b + db.
  using Vector9 = Eigen::Matrix<double, 9, 1>;
  using Matrix9x15 = Eigen::Matrix<double, 9, 15>;
  Vector9 residual(const NavState& i, const NavState& j, const ImuBias& b, const Eigen::Vector3d& g,
                   Matrix9x15* J_i = nullptr, Matrix9* J_j = nullptr) const;

  /// One sample's propagation of the preintegrated error (eq. 62): d' = A d + B eta_g + C eta_a, with
  /// d = [d_phi, d_v, d_p] at the start of the sample, for the bias-corrected sample (w, a) held for dt, at the
  /// preintegrated rotation dR before the sample.  Public for the tests and for graph factors.
  static void error_propagation(const Eigen::Matrix3d& dR, const Eigen::Vector3d& w, const Eigen::Vector3d& a,
                                double dt, Matrix9* A, Matrix93* B, Matrix93* C);

 private:
  /// The A of error_propagation from the sample's rotation increment dR_step = Exp(w dt).
  static void transition(const Eigen::Matrix3d& dR, const Eigen::Matrix3d& dR_step, const Eigen::Vector3d& a, double dt,
                         Matrix9& A);
  void propagate_jacobians(const Eigen::Matrix3d& dR_step, const Eigen::Matrix3d& Jr, const Eigen::Vector3d& a,
                           double dt);

  ImuBias bias_;
  ImuNoise noise_;
  double dt_ = 0;
  Eigen::Matrix3d dR_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv_ = Eigen::Vector3d::Zero(), dp_ = Eigen::Vector3d::Zero();
  Matrix9 cov_ = Matrix9::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero(), dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero(), dp_dba_ = Eigen::Matrix3d::Zero();
};

}  // namespace sextant::inertial
