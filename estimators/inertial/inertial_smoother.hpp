#pragma once
// A fixed-lag inertial keyframe smoother: IMU preintegration between keyframes, wheel-odometry increments, GNSS
// antenna positions, gravity in the model and the IMU biases estimated, over a sliding window of keyframes whose
// oldest is marginalized out (Schur complement, graph::marginalize) when the window is full, so that an update
// costs the same at the end of a day as at its start.  A plain library call: no I/O, no threads, no clock.
//
// The graph (estimators/inertial/inertial_factors.hpp for the factors and the variables of a keyframe):
//   - keyframe k: pose X_k (body to world, world = East-North-Up when GNSS is fused, z up), velocity v_k, gyroscope
//     and accelerometer biases b_g,k, b_a,k;
//   - between consecutive keyframes: ImuFactor (Forster et al. TRO 2017, eq. 45), a RandomWalkFactor per bias, and,
//     when both keyframes carry an odometry pose, the odometry increment (the SLAM layer's odometry_factor) with the
//     messages' increment covariances composed (lie/pose_covariance.hpp);
//   - on the keyframe before each fix: a robust GnssPositionFactor with the IMU preintegrated from the keyframe to
//     the fix's time, so every fix is used at its own time;
//   - on the oldest keyframe: the Gaussian prior of initialize(), later the marginalization's LinearPriorFactor.
// Each keyframe solves the window by Levenberg-Marquardt (graph::optimize) from the IMU-predicted new state.
//
// Keyframes: at an odometry message `keyframe_interval` seconds or more after the previous keyframe; at an IMU
// sample when odometry is not used or none came for 2 keyframe intervals.
//
// Observability (observability()): the marginal covariance of the newest keyframe's rotation in the world frame,
// from the window's information with every other variable marginalized: roll and pitch (the direction of gravity)
// are observable once their sigma is below `observable_tilt_sigma`, yaw once its sigma is below
// `observable_yaw_sigma`.  Gravity makes tilt observable from the accelerometer while the velocity is known
// (odometry, GNSS); yaw needs GNSS positions along a path that turns or accelerates (with IMU and odometry alone it
// stays at its prior).
//
// Input order: calls in non-decreasing time; a sample or message older than what it would modify (an IMU sample
// before the last one, odometry or a fix before the newest keyframe) is counted and dropped, as is a non-finite one.
#include "estimators/graph/robust_kernel.hpp"
#include "estimators/inertial/imu_preintegration.hpp"
#include "estimators/inertial/inertial_factors.hpp"
#include "estimators/inertial/sensor_mounting.hpp"
#include "estimators/lie/se3.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

namespace sextant::inertial {

struct InertialSmootherOptions {
  double keyframe_interval = 0.5;  // s
  int window = 20;                 // keyframes in the window (>= 2); older ones are marginalized
  ImuNoise noise;
  Eigen::Vector3d gravity{0, 0, -9.80665};                   // world frame, m/s^2
  bool use_odometry = true;                                  // keyframes at odometry messages, with odometry factors
  Eigen::Vector3d gnss_lever_arm = Eigen::Vector3d::Zero();  // antenna in the body frame, m
  graph::RobustKernel gnss_kernel = graph::RobustKernel::kHuber;
  double gnss_kernel_width = 2.7955;  // sqrt of chi-square(3)'s 95 % quantile: a fix beyond 2.8 sigma is down-weighted
  // The initial state's uncertainty (1 sigma; world frame: position m, velocity m/s, roll/pitch and yaw rad, biases).
  double initial_position_sigma = 1.0, initial_velocity_sigma = 0.5;
  double initial_tilt_sigma = 0.1, initial_yaw_sigma = 0.1;
  double initial_gyro_bias_sigma = 0.01, initial_accel_bias_sigma = 0.1;
  double observable_tilt_sigma = 0.02, observable_yaw_sigma = 0.05;  // rad
  int max_iterations = 10;                                           // Levenberg-Marquardt iterations per keyframe
};

/// Throws std::invalid_argument naming the first option out of range.
void check_options(const InertialSmootherOptions& o);

/// A keyframe's estimate.
struct KeyframeEstimate {
  double t = 0;  // s
  NavState state;
  ImuBias bias;
};

/// Whether gravity's direction (roll, pitch) and yaw are determined, with their marginal sigmas (rad, world frame).
struct Observability {
  double tilt_sigma = 0, yaw_sigma = 0;
  bool tilt = false, yaw = false;
};

/// Tilt and yaw sigmas of a pose with rotation R (body to world) and marginal covariance over [rho; phi], and
/// whether they are below the options' thresholds.
Observability observability_of(const Matrix6d& pose_covariance, const Eigen::Matrix3d& R,
                               const InertialSmootherOptions& options);

struct InertialSmootherCounters {
  int64_t keyframes = 0, marginalized = 0, imu = 0, odometry = 0, gnss = 0;
  int64_t odometry_links = 0;      // keyframe pairs joined by an odometry factor
  int64_t dropped = 0;             // out of order, before initialize() or non-finite
  int64_t gnss_down_weighted = 0;  // fixes beyond the kernel's width when their keyframe left the window
  int64_t failed_solves = 0;       // optimizer failures (the estimate kept its prediction)
  int64_t restarts = 0;  // keyframes that could not be added (a preintegration gone bad on absurd samples): the
                         // smoother started over from its newest keyframe's estimate
};

class InertialSmoother {
 public:
  explicit InertialSmoother(const InertialSmootherOptions& options);
  ~InertialSmoother();
  InertialSmoother(InertialSmoother&&) noexcept;
  InertialSmoother& operator=(InertialSmoother&&) noexcept;

  /// The first keyframe at time t with state x and bias b, and the prior of the options' initial sigmas; with
  /// `odometry_pose` (the wheel odometry's pose at t, in its own frame) the next keyframe gets an odometry factor.
  /// Called again, it starts over (the counters go on).  `sigmas`: the prior's position and yaw sigmas instead of
  /// the options' (a restart where GNSS determined them, gnss_heading.hpp).
  struct PriorSigmas {
    double position = 1, yaw = 0.1;  // m, rad
  };
  void initialize(double t, const NavState& x, const ImuBias& b = {}, std::optional<SE3> odometry_pose = {},
                  std::optional<PriorSigmas> sigmas = {});
  bool initialized() const;

  /// An IMU sample in the body frame at time t (held until the next: zero-order hold, as the filter).  False when
  /// dropped.
  bool add_imu(double t, const BodyImuSample& sample);
  /// The wheel odometry's pose at t in its own fixed frame, and the covariance of its increment since the previous
  /// message (tangent [t; phi] of the body, sextant's right perturbation; regularized by the caller).
  bool add_odometry(double t, const SE3& pose, const Matrix6d& increment_covariance);
  /// A GNSS antenna position at t in the world frame (ENU m, e.g. geodesy::LocalTangentPlane::to_enu of the fix)
  /// with its covariance, the antenna at `lever_arm` in the body frame (the options' gnss_lever_arm when not given).
  /// False when dropped (also when the covariance is not positive definite).
  bool add_gnss(double t, const Eigen::Vector3d& enu, const Eigen::Matrix3d& covariance,
                const std::optional<Eigen::Vector3d>& lever_arm = std::nullopt);

  /// The newest keyframe's estimate, and the state at the last IMU sample predicted from it.
  KeyframeEstimate newest() const;
  NavState current() const;
  double current_time() const;
  /// The keyframes in the window, oldest first.
  std::vector<KeyframeEstimate> window() const;
  /// The newest keyframe pose's marginal covariance over its tangent [rho; phi] (body frame, right perturbation),
  /// with every other variable of the window marginalized: one dense elimination of the window, computed on call.
  Matrix6d newest_pose_covariance() const;
  /// observability_of the newest pose (see the file comment); computed on call as newest_pose_covariance().
  Observability observability() const;
  const InertialSmootherCounters& counters() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
  void add_keyframe_or_restart(double t, const std::optional<SE3>& odometry);
};

}  // namespace sextant::inertial
