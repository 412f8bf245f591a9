#pragma once
// The filter stage: one planar EKF per body (estimators/filter/multi_source_ekf.hpp).  odometry_t.source names an
// odometry source; `FilterConfig::sources` maps sources to bodies (an unlisted source is a body of its own).  The
// body's predicting source drives the prediction and publishes a FusedPose "ekf" (source = the body) at its rate;
// its other sources are fused as differential increments, absolute poses or integrated twists, with their masks,
// gates and timeouts; landmark sightings (landmarks_t.source: the body, or one of its sources) update.  The
// covariance published is converted from the filter's (x, y, theta) parameterization to sextant's right
// perturbation in the body frame.
//
// Late measurements (estimators/filter/measurement_history.hpp): each body keeps `history_s` of its inputs; an
// odometry message or a sighting older than the newest input but inside that window is inserted in time order and
// everything after it re-applied (equal stamps: the predicting source, then other sources, then sightings), so the
// result is the one in-order arrival gives.  A pose is published only for the newest prediction (published stamps
// never go backwards; a late correction shows in the next one).  Older than the window: counted as "too_late" and
// dropped.  A second odometry message of a source with the same utime is counted as "duplicate_stamps".
// Sightings taken between two predictions wait for the next one, which is split at their stamps (interpolated on
// SE(2)) so that they update the pose they were taken from (applied at the previous prediction instead, a 2 m/s
// robot with 50 Hz odometry and 10 Hz sightings was 1 cm off and its NEES four times too large).  At most 64
// batches wait; older ones are dropped and counted ("sightings_without_prediction").
// 3-D bodies (odometry_t.planar false) get a 3-D EKF (estimators/filter/spatial_ekf.hpp): their predicting source's
// increments, range/azimuth/elevation sightings with ids (EKF-SLAM; sightings without id are counted as
// "unidentified_3d"; the planar known map does not apply), the same history and sighting interpolation, and a
// FusedPose with the full 6x6 covariance.  Only the predicting source of a 3-D body is used (its other sources are
// counted as "unfused_3d"); a body that mixes planar and 3-D messages keeps the kind it started with and counts
// the others as "mixed_dimensions".
// Every prediction, update and landmark addition that would leave a body's estimate non-finite or its covariance
// indefinite is undone by the filter and counted ("refused_non_finite", "refused_indefinite"; estimate_health.hpp):
// the body continues from its last healthy state and nothing unhealthy is published.
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/filter/measurement_history.hpp"
#include "estimators/filter/multi_source_ekf.hpp"
#include "estimators/filter/spatial_ekf.hpp"
#include "estimators/filter/spatial_fusion.hpp"

#include <map>

namespace sextant::engine {

class FilterStage final : public Stage {
 public:
  explicit FilterStage(const FilterConfig& config) : config_(config) {}
  StageKind kind() const override { return StageKind::kFilter; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kEkf; }
  bool accepts(const Event& e) const override {
    return std::holds_alternative<Odometry>(e) || std::holds_alternative<LandmarkSightings>(e);
  }
  void handle(const Event& e, const Emit& emit) override;
  /// Forgets the failed event's body (its filter restarts from its next odometry message).
  void recover(const Event& failed) override;
  /// A body of its own (a source `sources` does not list) is forgotten; the configured bodies stay.
  void forget(const std::string& source) override {
    if (config_.sources.contains(source)) return;
    histories_.erase(source);
    spatial_.erase(source);
    published_.erase(source);
  }
  Counters counters() const override;
  /// The state directory (filter_stage_state.cpp): every body's filter with its window of recent inputs and
  /// checkpoints (late inputs are re-applied after a restart as before it), what was published, the counters.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;

  /// The landmark estimates of a body's filter (known map and SLAM landmarks).
  std::map<int64_t, Eigen::Vector2d> landmarks(const std::string& body) const;
  /// The current EKF of a body (nullptr before its first prediction), for tests.
  const filter::PlanarEkf* ekf(const std::string& body) const;
  const filter::SpatialEkf* spatial_ekf(const std::string& body) const;
  /// The body an odometry source (or a sightings' source) belongs to.
  std::string body_of(const std::string& source) const;

 private:
  // Everything one body's filter has consumed, counters included: the history copies it into checkpoints and
  // re-applies inputs to it, so re-application never counts twice.
  struct Track {
    filter::MultiSourceEkf fusion;
    std::vector<LandmarkSightings> pending;  // taken after the newest prediction: applied inside the next one
    int64_t predictions = 0, updates = 0, gated = 0, new_landmarks = 0, unknown = 0, rejected = 0, before_odometry = 0,
            associated = 0, tentative = 0, duplicates = 0, unknown_sources = 0, stale_sightings = 0, over_budget = 0,
            exhausted = 0;
    void save(archive::ArchiveWriter& w) const;
    void load(archive::ArchiveReader& r);
  };
  using Input = std::variant<Odometry, LandmarkSightings>;
  using History = filter::MeasurementHistory<Track, Input>;
  // A 3-D body: the same, with the 3-D filter driven by its predicting source (estimators/filter/spatial_fusion.hpp).
  struct SpatialTrack {
    filter::SpatialFusion fusion;
    std::vector<LandmarkSightings> pending;  // taken after the newest prediction: applied inside the next one
    int64_t predictions = 0, updates = 0, gated = 0, new_landmarks = 0, rejected = 0, before_odometry = 0,
            duplicates = 0, unidentified = 0, unfused = 0, stale_sightings = 0, over_budget = 0;
    void save(archive::ArchiveWriter& w) const;
    void load(archive::ArchiveReader& r);
  };
  using SpatialHistory = filter::MeasurementHistory<SpatialTrack, Input>;

  Track new_track(const std::string& body) const;
  void apply(Track& t, const Input& in) const;
  void apply_odometry(Track& t, const Odometry& o) const;
  void apply_landmarks(Track& t, const LandmarkSightings& s) const;
  void update_with(Track& t, const LandmarkSightings& s) const;
  void publish(const std::string& body, const Track& t, const Emit& emit) const;
  bool predicts(const std::string& source) const;
  SpatialTrack new_spatial_track() const;
  void apply(SpatialTrack& t, const Input& in) const;
  void update_with(SpatialTrack& t, const LandmarkSightings& s) const;
  void publish(const std::string& body, const SpatialTrack& t, const Emit& emit) const;
  template <class H>
  void add(H& history, const std::string& body, int64_t utime, int rank, Input in, const Emit& emit);

  FilterConfig config_;
  std::map<std::string, History> histories_;       // by body
  std::map<std::string, SpatialHistory> spatial_;  // 3-D bodies
  std::map<std::string, int64_t> published_;       // newest utime published per body
  int64_t mixed_ = 0, before_odometry_ = 0, too_late_ = 0, reapplied_ = 0;
};

}  // namespace sextant::engine
