#pragma once
// FUSED_POSE "graph" at the odometry rate: the latest map -> odometry correction of the graph back end
// (graph_correction.hpp) composed with each odometry pose,
//     T_map(t) = T_map(kf) (T_odom(kf)^-1 T_odom(t)),
// with covariance Ad(D^-1) P_kf Ad(D^-1)' + Q_D, D = T_odom(kf)^-1 T_odom(t), P_kf the keyframe's marginal and Q_D the
// odometry's own growth since the keyframe (its pose covariance minus the transported one, PSD-projected).  Before
// the first correction a body's odometry frame is its map frame.  The intake gives each body's odometry in strictly
// increasing time, and the publisher refuses a pose at or before the last one published (its one rule), so the
// stage keeps no per-body time.  A pose that is not finite or whose covariance is indefinite (estimate_health.hpp: a
// correction or an odometry message gone wrong) is not published and is counted ("refused_non_finite",
// "refused_indefinite").  A stage of its own so that it runs on its own thread in the daemon, never behind a solve.
#include "daemon/engine/graph_correction.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/filter/estimate_health.hpp"

#include <algorithm>
#include <memory>
#include <vector>

namespace sextant::engine {

class GraphPoseStage final : public Stage {
 public:
  explicit GraphPoseStage(std::shared_ptr<const GraphCorrectionBoard> corrections)
      : corrections_(std::move(corrections)) {}
  StageKind kind() const override { return StageKind::kGraphPose; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kGraph; }
  bool accepts(const Event& e) const override { return std::holds_alternative<Odometry>(e); }
  void handle(const Event& e, const Emit& emit) override;
  /// The state directory: the counters (the correction itself is the graph stage's).
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;
  Counters counters() const override {
    int64_t age_max = 0;
    for (int64_t a : correction_ages_) age_max = std::max(age_max, a);
    return {{"published", published_},
            {"before_correction", before_correction_},
            {"correction_age_us",
             correction_ages_.empty()
                 ? 0
                 : correction_ages_[(age_next_ + correction_ages_.size() - 1) % correction_ages_.size()]},
            {"correction_age_us_max", age_max},
            {"refused_non_finite", refusals_.non_finite},
            {"refused_indefinite", refusals_.indefinite}};
  }

 private:
  std::shared_ptr<const GraphCorrectionBoard> corrections_;
  int64_t published_ = 0, before_correction_ = 0;
  /// Data time from the correction's keyframe to the odometry it was applied to (how far the graph lags the fused
  /// pose): the last value and the largest of the last 1024 (status: correction_age_us, correction_age_us_max).
  static constexpr size_t kAgeRing = 1024;
  void record_correction_age(int64_t age_us) {
    if (correction_ages_.size() < kAgeRing)
      correction_ages_.push_back(age_us), age_next_ = correction_ages_.size() % kAgeRing;
    else
      correction_ages_[age_next_] = age_us, age_next_ = (age_next_ + 1) % kAgeRing;
  }
  std::vector<int64_t> correction_ages_;
  size_t age_next_ = 0;
  filter::Refusals refusals_;
};

}  // namespace sextant::engine
