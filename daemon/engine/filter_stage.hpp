#pragma once
// The filter stage: one planar EKF (estimators/filter/planar_ekf.hpp) per odometry source.  Odometry predicts
// (the increment between consecutive odometry poses, with the message's increment covariance) and publishes a
// FusedPose "ekf" at the odometry rate; landmark sightings update.  The covariance published is converted from the
// filter's (x, y, theta) parameterization to sextant's right perturbation in the body frame.
// 3-D sources are not handled yet (counted as "not_planar").
#include "daemon/engine/filter_stage_config.hpp"
#include "daemon/engine/stage.hpp"
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

 private:
  struct Track {
    filter::PlanarEkf ekf;
    SE2 last_odom;
    Matrix6 last_covariance = Matrix6::Zero();
    int64_t utime = 0;
  };
  void on_odometry(const Odometry& o, const Emit& emit);
  void on_landmarks(const LandmarkSightings& s);

  FilterConfig config_;
  std::map<std::string, Track> tracks_;
  int64_t predictions_ = 0, updates_ = 0, gated_ = 0, new_landmarks_ = 0, unknown_ = 0, rejected_ = 0,
          not_planar_ = 0, before_odometry_ = 0, associated_ = 0, tentative_ = 0;
};

}  // namespace sextant::engine
