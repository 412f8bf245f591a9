#pragma once
// A 3-D extended Kalman filter (error state on SE(3)) for a body with range/azimuth/elevation landmark sightings:
// EKF-SLAM with state augmentation, sharing the Joseph-form update of kalman_update.hpp with the planar filter.
// State: the pose X (nominal, an SE(3) element) and landmarks l_i in the map frame; the covariance is over
// [xi, l_1, l_2, ...] with xi = [rho, phi] the right perturbation of the pose, X_true = X * Exp(xi) (sextant's
// convention: translation first, body frame), so the pose block is directly the FUSED_POSE covariance.
//  - Motion: X' = X * Delta * Exp(w), w ~ N(0, Q) (the increment covariance of odometry_t): xi' = Ad(Delta^-1) xi + w,
//    F = Ad(Delta^-1), G = I (Sola et al., arXiv:1812.01537, eq. 180).
//  - Observation of landmark l: q = R^T (l - t) in the body frame, h = [|q|, atan2(qy, qx), atan2(qz, |qxy|)]
//    (the simulator's and landmarks_t's azimuth/elevation), dq/drho = -I, dq/dphi = [q]x, dq/dl = R^T; the
//    azimuth innovation wrapped to (-pi, pi].
//  - New landmark: l = t + R q(z), q(z) = r [cos(el) cos(az), cos(el) sin(az), sin(el)].
// The sensor is taken at the body origin (landmarks_t.sensor_in_body is not applied, as in the planar filter).
// Update: the error state dx = K r is applied as X <- X Exp(dxi), l <- l + dl (the error state is reset to 0).
#include "estimators/archive/binary_archive.hpp"
#include "estimators/filter/estimate_health.hpp"
#include "estimators/filter/kalman_update.hpp"
#include "estimators/lie/se3.hpp"

#include <algorithm>
#include <map>

namespace sextant::filter {

struct SpatialEkfOptions {
  double gate = 11.34;  // chi-square (3 dof) threshold on the normalized innovation; 11.34 = 99 %
  bool slam = true;     // new landmark ids are added to the state
  int max_landmarks = 4096;
  double update_budget = 5e8;  // as PlanarEkfOptions::update_budget (kalman_update.hpp, UpdateBudget)
};

class SpatialEkf {
 public:
  using Matrix6 = SE3::Matrix6;
  explicit SpatialEkf(const SpatialEkfOptions& options = {}) : options_(options) {}

  void initialize(const SE3& pose, const Matrix6& covariance);
  bool initialized() const { return initialized_; }

  /// The motion model above; refused (state unchanged, counted, returned) when its result would not be finite or
  /// its pose covariance not positive semi-definite (estimate_health.hpp).
  Health predict(const SE3& delta, const Matrix6& Q);
  /// A range/azimuth/elevation sighting of landmark `id` (R over [range, azimuth, elevation]).  A landmark in the
  /// state updates; a new one is added (SLAM mode).  Refused ("gate", "non_finite", "singular", "unknown_landmark",
  /// "map_full") otherwise.
  UpdateResult observe(int64_t id, const Eigen::Vector3d& z, const Eigen::Matrix3d& R);

  const SE3& pose() const { return pose_; }
  Matrix6 pose_covariance() const { return P_.topLeftCorner<6, 6>(); }
  const Eigen::MatrixXd& covariance() const { return P_; }
  std::map<int64_t, Eigen::Vector3d> landmarks() const;
  size_t landmark_count() const { return slot_.size(); }
  /// Predictions, updates and landmark additions refused because of what they would have done to the estimate.
  const Refusals& refusals() const { return refusals_; }
  /// A batch's budget (the options' update_budget); `size()` is what an update is charged by.
  UpdateBudget new_update_budget() const { return UpdateBudget(options_.update_budget); }
  Eigen::Index size() const { return P_.rows(); }

  /// The models and their Jacobians (for tests).  `observation`: H_pose = dh/dxi, H_landmark = dh/dl.
  static Eigen::Vector3d observation(const SE3& pose, const Eigen::Vector3d& landmark,
                                     Eigen::Matrix<double, 3, 6>* H_pose, Eigen::Matrix3d* H_landmark);
  /// The landmark seen at z from `pose`, with J_pose = dl/dxi and J_z = dl/dz.
  static Eigen::Vector3d inverse_observation(const SE3& pose, const Eigen::Vector3d& z,
                                             Eigen::Matrix<double, 3, 6>* J_pose, Eigen::Matrix3d* J_z);

  /// The filter's state (estimate, covariance, landmarks) in the binary archive (the daemon's state directory); the
  /// options are the constructor's.
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  Health augment(int64_t id, const Eigen::Vector3d& z, const Eigen::Matrix3d& R);
  UpdateResult counted(UpdateResult r);

  SpatialEkfOptions options_;
  bool initialized_ = false;
  SE3 pose_;
  Eigen::VectorXd landmarks_;  // [l1, l2, ...], 3 each; covariance index = 6 + index here
  Eigen::MatrixXd P_ = Eigen::MatrixXd::Identity(6, 6);
  std::map<int64_t, int> slot_;  // landmark id -> index of its x in the covariance
  Refusals refusals_;
};

}  // namespace sextant::filter
