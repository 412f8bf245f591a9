#pragma once
// The particle filter stage (`filter: {type: pf}`): one FastSLAM 2.0 filter (estimators/filter/fastslam.hpp) per
// odometry source.  Odometry predicts (the increment between consecutive odometry poses, with the increment
// covariance of planar_pose_covariance.hpp) and publishes a FusedPose "pf" at the odometry rate: the particles'
// weighted mean, and the covariance of the particle mixture converted to sextant's body-frame right perturbation
// (planar_covariance_in_body_frame, the EKF stage's conversion).  Landmark sightings of one message are one batch
// (improved proposal, landmark updates, resampling).  The map frame is the first odometry pose; `filter.map`
// gives known landmarks in it (localization), `filter.slam` adds the others.  3-D sources are counted
// ("not_planar") and dropped; the sensor is taken at the body origin (sensor_in_body is not applied).
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/stage.hpp"
#include "estimators/filter/fastslam.hpp"

#include <map>

namespace sextant::engine {

class ParticleFilterStage final : public Stage {
 public:
  explicit ParticleFilterStage(const FilterConfig& config) : config_(config) {}
  StageKind kind() const override { return StageKind::kParticleFilter; }
  std::optional<PrimaryEstimator> estimator_kind() const override { return PrimaryEstimator::kPf; }
  bool accepts(const Event& e) const override {
    return std::holds_alternative<Odometry>(e) || std::holds_alternative<LandmarkSightings>(e);
  }
  void handle(const Event& e, const Emit& emit) override;
  /// Forgets the failed event's source (its filter restarts from its next odometry message).
  void recover(const Event& failed) override { tracks_.erase(event_source(failed)); }
  void forget(const std::string& source) override { tracks_.erase(source); }
  Counters counters() const override;
  /// The state directory: every source's particle filter (particles, maps, random generator) and the counters.
  void save(archive::ArchiveWriter& w) override;
  void load(archive::ArchiveReader& r) override;

  /// The landmark estimates of a source's filter (its particle of largest weight, plus the known map).
  std::map<int64_t, Eigen::Vector2d> landmarks(const std::string& source) const;
  /// The filter of a source, or nullptr (for tests).
  const filter::FastSlam* filter(const std::string& source) const;

 private:
  struct Track {
    filter::FastSlam pf;
    SE2 last_odom;
    Matrix6 last_covariance = Matrix6::Zero();
    int64_t utime = 0;
  };
  void on_odometry(const Odometry& o, const Emit& emit);
  filter::FastSlamOptions fastslam_options() const;
  void on_landmarks(const LandmarkSightings& s);

  FilterConfig config_;
  std::map<std::string, Track> tracks_;
  int64_t predictions_ = 0, bad_odometry_ = 0, out_of_order_ = 0, updates_ = 0, new_landmarks_ = 0, associated_ = 0,
          gated_ = 0, rejected_ = 0, unknown_ = 0, removed_ = 0, resamplings_ = 0, not_planar_ = 0,
          before_odometry_ = 0;
  filter::Refusals refusals_;
  int64_t over_budget_ =
      0;  // sightings without id dropped by FastSlamOptions::association_budget  // steps undone because they left the filter unhealthy (FastSlam::health)
};

}  // namespace sextant::engine
