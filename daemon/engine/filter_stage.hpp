#pragma once
// The filter stage: one planar EKF (estimators/filter/planar_ekf.hpp) per odometry source.  Odometry predicts
// (the increment between consecutive odometry poses, with the message's increment covariance) and publishes a
// FusedPose "ekf" at the odometry rate; landmark sightings update.  The covariance published is converted from the
// filter's (x, y, theta) parameterization to sextant's right perturbation in the body frame.
//
// Late measurements (estimators/filter/measurement_history.hpp): each filter keeps `history_s` of its inputs; an
// odometry message or a sighting older than the newest input but inside that window is inserted in time order and
// everything after it re-applied (equal stamps: odometry before sightings), so the result is the one in-order
// arrival gives.  A pose is published only for the newest odometry (published stamps never go backwards; a late
// correction shows in the next one).  Older than the window: counted as "too_late" and dropped.  A second odometry
// message of a source with the same utime is counted as "duplicate_stamps" and dropped.
// 3-D sources are not handled yet (counted as "not_planar").
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/filter/measurement_history.hpp"
#include "estimators/filter/planar_ekf.hpp"

#include <map>

namespace sextant::engine {

class FilterStage final : public Stage {
 public:
  explicit FilterStage(const FilterConfig& config) : config_(config) {}
  std::string_view name() const override { return "filter"; }
  std::string_view estimator() const override { return "ekf"; }
  bool accepts(const Event& e) const override {
    return std::holds_alternative<Odometry>(e) || std::holds_alternative<LandmarkSightings>(e);
  }
  void handle(const Event& e, const Emit& emit) override;
  Counters counters() const override;

  /// The landmark estimates of a source's filter (known map and SLAM landmarks).
  std::map<int64_t, Eigen::Vector2d> landmarks(const std::string& source) const;
  /// The current EKF of a source (nullptr before its first odometry message), for tests.
  const filter::PlanarEkf* ekf(const std::string& source) const;

 private:
  // Everything one filter has consumed, counters included: the history copies it into checkpoints and re-applies
  // inputs to it, so re-application never counts twice.
  struct Track {
    filter::PlanarEkf ekf;
    bool started = false;
    SE2 last_odom;
    Matrix6 last_covariance = Matrix6::Zero();
    int64_t utime = 0;  // of the newest odometry applied
    int64_t predictions = 0, updates = 0, gated = 0, new_landmarks = 0, unknown = 0, rejected = 0,
            before_odometry = 0, associated = 0, tentative = 0, duplicates = 0;
  };
  using Input = std::variant<Odometry, LandmarkSightings>;
  using History = filter::MeasurementHistory<Track, Input>;

  void apply(Track& t, const Input& in) const;
  void apply_odometry(Track& t, const Odometry& o) const;
  void apply_landmarks(Track& t, const LandmarkSightings& s) const;
  void publish(const std::string& source, const Track& t, const Emit& emit) const;

  FilterConfig config_;
  std::map<std::string, History> histories_;
  std::map<std::string, int64_t> published_;  // newest utime published per source
  int64_t not_planar_ = 0, before_odometry_ = 0, too_late_ = 0, reapplied_ = 0;
};

}  // namespace sextant::engine
