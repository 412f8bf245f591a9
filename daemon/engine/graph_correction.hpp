#pragma once
// The map -> odometry correction the graph back end hands to the fused-pose path.  The graph stage writes it after
// every optimization (the newest keyframe's optimized pose, its odometry pose and both covariances); the graph
// pose stage reads it for every odometry message and publishes
//     T_map(t) = T_map(kf) * (T_odom(kf)^-1 * T_odom(t)).
// Both stages see the board through GraphCorrectionBoard.  In replay (one thread) it is GraphCorrections, a map; the
// daemon runs the two stages on different threads (so a long optimization delays only the correction, never the
// fused pose) and gives them a board that guards the map (daemon/runtime/shared_graph_corrections.hpp).
#include "daemon/engine/events.hpp"
#include "estimators/lie/se3.hpp"

#include <map>
#include <optional>
#include <string>

namespace sextant::engine {

struct GraphCorrection {
  int64_t keyframe_utime = 0;
  SE3 keyframe_odom;                                   // the keyframe's pose in the odometry frame
  SE3 keyframe_map;                                    // its optimized pose in the map frame
  Matrix6 keyframe_covariance = Matrix6::Zero();       // marginal covariance of keyframe_map (right perturbation)
  Matrix6 keyframe_odom_covariance = Matrix6::Zero();  // the odometry message's pose covariance at the keyframe
  std::string frame;  // the map frame of keyframe_map (its root body: the body itself, or the fleet's frame)
};

/// Each body's latest correction: the graph stage writes, the graph pose stage reads.
class GraphCorrectionBoard {
 public:
  virtual ~GraphCorrectionBoard() = default;
  virtual void set(const std::string& source, const GraphCorrection& c) = 0;
  virtual void erase(const std::string& source) = 0;
  virtual std::optional<GraphCorrection> get(const std::string& source) const = 0;
};

/// The board of one thread: a map by body.
class GraphCorrections final : public GraphCorrectionBoard {
 public:
  void set(const std::string& source, const GraphCorrection& c) override { corrections_[source] = c; }
  void erase(const std::string& source) override { corrections_.erase(source); }
  std::optional<GraphCorrection> get(const std::string& source) const override {
    auto it = corrections_.find(source);
    if (it == corrections_.end()) return std::nullopt;
    return it->second;
  }

 private:
  std::map<std::string, GraphCorrection> corrections_;
};

}  // namespace sextant::engine
