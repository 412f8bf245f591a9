#pragma once
// The map -> odometry correction the graph back end hands to the fused-pose path.  The graph stage writes it after
// every optimization (the newest keyframe's optimized pose, its odometry pose and both covariances); the graph
// pose stage reads it for every odometry message and publishes
//     T_map(t) = T_map(kf) * (T_odom(kf)^-1 * T_odom(t)).
// The two stages run on different threads in the daemon (so a long optimization delays only the correction, never
// the fused pose): the board is the one piece of state they share, behind a mutex held only to copy an entry.
#include "daemon/engine/events.hpp"
#include "estimators/lie/se3.hpp"

#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace sextant::engine {

struct GraphCorrection {
  int64_t keyframe_utime = 0;
  SE3 keyframe_odom;                                  // the keyframe's pose in the odometry frame
  SE3 keyframe_map;                                   // its optimized pose in the map frame
  Matrix6 keyframe_covariance = Matrix6::Zero();      // marginal covariance of keyframe_map (right perturbation)
  Matrix6 keyframe_odom_covariance = Matrix6::Zero(); // the odometry message's pose covariance at the keyframe
};

class GraphCorrections {
 public:
  void set(const std::string& source, const GraphCorrection& c) {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections_[source] = c;
  }
  void erase(const std::string& source) {
    std::lock_guard<std::mutex> lock(mutex_);
    corrections_.erase(source);
  }
  std::optional<GraphCorrection> get(const std::string& source) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = corrections_.find(source);
    if (it == corrections_.end()) return std::nullopt;
    return it->second;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, GraphCorrection> corrections_;
};

}  // namespace sextant::engine
