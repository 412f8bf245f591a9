#pragma once
// Between the engine's message-level Pose (position + quaternion) and the Lie group the estimators compute with.
#include "daemon/engine/events.hpp"
#include "estimators/lie/se3.hpp"

namespace sextant::engine {

inline SE3 to_se3(const Pose& p) { return SE3(p.orientation, p.position); }

inline Pose to_pose(const SE3& x) {
  Pose p;
  p.position = x.translation();
  p.orientation = x.rotation().quaternion();
  return p;
}

}  // namespace sextant::engine
