#pragma once
// A 3-D body's filter driven by one predicting odometry source, as MultiSourceEkf drives the planar one: the
// source's first message starts the SpatialEkf at its pose with the initial covariance; each later message (a later
// time) predicts with the motion since the previous one, Delta = T_prev^-1 T, and its increment covariance (the
// stated one, or the growth of the pose covariance, regularized: estimators/lie/pose_covariance.hpp,
// regularized_increment_covariance), split at the times of sightings taken in between (interpolated_prediction.hpp)
// so that each is applied at the pose it was taken from.  The sightings themselves wait in the caller until the
// prediction reaches them.
#include "estimators/archive/binary_archive.hpp"
#include "estimators/filter/spatial_ekf.hpp"
#include "estimators/lie/lie_archive.hpp"
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace sextant::filter {

/// One odometry message of the predicting source: its pose in the source's frame and the covariances over
/// [rho, phi] (right perturbation, body frame).
struct SpatialOdometry {
  int64_t utime = 0;
  SE3 pose;
  SE3::Matrix6 covariance = SE3::Matrix6::Zero();
  std::optional<SE3::Matrix6> increment_covariance;  // since the previous message
};

/// What happened to one odometry message.
enum class SpatialOdometryOutcome {
  kStarted,    // the first message: the filter starts at its pose
  kPredicted,  // a later message: predicted to it
  kDuplicate,  // not newer than the previous message: ignored
};

class SpatialFusion {
 public:
  using Matrix6 = SE3::Matrix6;
  SpatialFusion() = default;
  SpatialFusion(const SpatialEkfOptions& options, const Matrix6& initial_covariance, double min_increment_variance)
      : ekf_(options), initial_covariance_(initial_covariance), min_variance_(min_increment_variance) {}

  /// One message; for a prediction, `at_stop(i)` runs with the state predicted to stops[i] (utimes strictly between
  /// the previous message and this one, increasing; others are skipped).
  SpatialOdometryOutcome odometry(const SpatialOdometry& m, const std::vector<int64_t>& stops,
                                  const std::function<void(size_t)>& at_stop);

  bool started() const { return started_; }
  int64_t utime() const { return utime_; }  // of the newest message
  SpatialEkf& ekf() { return ekf_; }
  const SpatialEkf& ekf() const { return ekf_; }

  /// The state (the EKF, whether started, the previous message's pose, covariance and time) in the binary archive;
  /// the options are the constructor's.
  void save(archive::ArchiveWriter& w) const { w(ekf_)(started_)(last_pose_)(last_covariance_)(utime_); }
  void load(archive::ArchiveReader& r) { r(ekf_)(started_)(last_pose_)(last_covariance_)(utime_); }

 private:
  SpatialEkf ekf_;
  Matrix6 initial_covariance_ = Matrix6::Identity();
  double min_variance_ = 1e-10;
  bool started_ = false;
  SE3 last_pose_;
  Matrix6 last_covariance_ = Matrix6::Zero();
  int64_t utime_ = 0;
};

}  // namespace sextant::filter
