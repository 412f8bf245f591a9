#include "estimators/filter/spatial_fusion.hpp"

#include "estimators/filter/interpolated_prediction.hpp"
#include "estimators/lie/pose_covariance.hpp"

namespace sextant::filter {

SpatialOdometryOutcome SpatialFusion::odometry(const SpatialOdometry& m, const std::vector<int64_t>& stops,
                                               const std::function<void(size_t)>& at_stop) {
  SpatialOdometryOutcome outcome = SpatialOdometryOutcome::kStarted;
  if (!started_) {
    ekf_.initialize(m.pose, initial_covariance_);
    started_ = true;
  } else {
    if (m.utime <= utime_) return SpatialOdometryOutcome::kDuplicate;
    const SE3 delta = last_pose_.between(m.pose);
    const Matrix6 Q = regularized_increment_covariance(m.covariance, m.increment_covariance, /*planar=*/false, delta,
                                                       last_covariance_, min_variance_);
    predict_through_stops(
        delta, Q, utime_, m.utime, stops, [this](const SE3& piece, const Matrix6& q) { ekf_.predict(piece, q); },
        at_stop);
    outcome = SpatialOdometryOutcome::kPredicted;
  }
  last_pose_ = m.pose;
  last_covariance_ = m.covariance;
  utime_ = m.utime;
  return outcome;
}

}  // namespace sextant::filter
