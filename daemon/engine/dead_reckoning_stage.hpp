#pragma once
// Dead reckoning: per odometry source, the increments Delta_k = T_odom(k-1)^-1 * T_odom(k) composed into a pose in
// the map frame, M(k) = M(k-1) * Delta_k, with first-order covariance propagation for the right perturbation
// (Sola et al., "A micro Lie theory", arXiv 1812.01537, eq. 55 and the adjoint of eq. 29):
//     P(k) = Ad(Delta_k^-1) P(k-1) Ad(Delta_k^-1)^T + Q_k,
// where Q_k is the message's increment covariance, or, when the sender gives none, the part of its pose covariance
// that grew since the previous message (Sigma_k - Ad(Delta^-1) Sigma_(k-1) Ad(Delta^-1)^T, projected onto the
// positive semi-definite cone).  The map frame of a source is its odometry frame at its first message.
// Planar sources use the same SE(3) algebra with zero z, roll and pitch: their x, y, yaw block is SE(2)'s.
// A message whose step would leave the pose non-finite or its covariance indefinite (estimate_health.hpp) is
// refused: nothing is published, the track stays as it was (the next message's increment starts from the last
// accepted one), and it is counted ("refused_non_finite", "refused_indefinite").
#include "daemon/engine/dead_reckoning_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/filter/estimate_health.hpp"
#include "estimators/lie/se3.hpp"

#include <map>

namespace sextant::engine {

class DeadReckoningStage final : public Stage {
 public:
  explicit DeadReckoningStage(const DeadReckoningConfig& config) : config_(config) {}

  StageKind kind() const override { return StageKind::kDeadReckoning; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kDeadReckoning; }
  bool accepts(const Event& e) const override { return std::holds_alternative<Odometry>(e); }
  void handle(const Event& e, const Emit& emit) override;
  /// Forgets the failed event's source (it restarts from its next odometry message).
  void recover(const Event& failed) override { tracks_.erase(event_source(failed)); }
  void forget(const std::string& source) override { tracks_.erase(source); }
  Counters counters() const override;
  /// The state directory: every source's track and the counters.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;

  /// One step of the propagation above, exposed for tests: returns P(k).
  static Matrix6 propagate(const Matrix6& previous, const SE3& increment, const Matrix6& increment_covariance);

 private:
  struct Track {
    int64_t utime = 0;
    SE3 last_odom;
    Matrix6 last_odom_covariance = Matrix6::Zero();
    SE3 map_pose;
    Matrix6 covariance = Matrix6::Zero();
  };
  DeadReckoningConfig config_;
  std::map<std::string, Track> tracks_;
  int64_t gaps_ = 0;
  int64_t processed_ = 0;
  filter::Refusals refusals_;
};

}  // namespace sextant::engine
