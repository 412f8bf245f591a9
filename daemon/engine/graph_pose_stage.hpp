#pragma once
// FUSED_POSE "graph" at the odometry rate: the latest map -> odometry correction of the graph back end
// (graph_correction.hpp) composed with each odometry pose,
//     T_map(t) = T_map(kf) (T_odom(kf)^-1 T_odom(t)),
// with covariance Ad(D^-1) P_kf Ad(D^-1)' + Q_D, D = T_odom(kf)^-1 T_odom(t), P_kf the keyframe's marginal and Q_D the
// odometry's own growth since the keyframe (its pose covariance minus the transported one, PSD-projected).  Before
// the first correction a body's odometry frame is its map frame.  Never publishes a utime at or before the last one
// of the same body.  A stage of its own so that it runs on its own thread in the daemon, never behind a solve.
#include "daemon/engine/graph_correction.hpp"
#include "daemon/engine/stage.hpp"

#include <map>
#include <memory>

namespace sextant::engine {

class GraphPoseStage final : public Stage {
 public:
  explicit GraphPoseStage(std::shared_ptr<const GraphCorrections> corrections) : corrections_(std::move(corrections)) {}
  std::string_view name() const override { return "graph_pose"; }
  std::string_view estimator() const override { return "graph"; }
  bool accepts(const Event& e) const override { return std::holds_alternative<Odometry>(e); }
  void handle(const Event& e, const Emit& emit) override;
  Counters counters() const override {
    return {{"published", published_}, {"out_of_order", out_of_order_}, {"before_correction", before_correction_}};
  }

 private:
  std::shared_ptr<const GraphCorrections> corrections_;
  std::map<std::string, int64_t> last_utime_;
  int64_t published_ = 0, out_of_order_ = 0, before_correction_ = 0;
};

}  // namespace sextant::engine
