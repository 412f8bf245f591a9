#pragma once
// The subscriber's side of TRAJECTORY (trajectory_t.lcm states the rule): a body's current keyframes rebuilt from the
// UPDATE and SNAPSHOT messages, fed in sequence order.  Each keyframe of a message replaces the one with its id,
// removed ids are erased, and a SNAPSHOT chunk also erases the ids in [range_first, range_last] that it does not
// carry.  One per body (and sender); tests/e2e/lcmlog.py has the same in Python.
#include "daemon/engine/outputs.hpp"

#include <map>
#include <vector>

namespace sextant::engine {

class TrajectoryRebuild {
 public:
  void add(const Trajectory& t) {
    if (t.kind == Trajectory::Kind::kSnapshot) {
      std::map<int64_t, Keyframe> carried;
      for (const auto& k : t.keyframes) carried.emplace(k.id, k);
      for (auto it = held_.lower_bound(t.range_first); it != held_.end() && it->first <= t.range_last;)
        it = carried.count(it->first) ? std::next(it) : held_.erase(it);
    }
    for (int64_t id : t.removed_ids) held_.erase(id);
    for (const auto& k : t.keyframes) held_[k.id] = k;
    total_keyframes_ = t.total_keyframes;
  }
  /// The keyframes held, by id.
  const std::map<int64_t, Keyframe>& keyframes() const { return held_; }
  /// The trajectory size the last message announced (-1 before any).
  int total_keyframes() const { return total_keyframes_; }

 private:
  std::map<int64_t, Keyframe> held_;
  int total_keyframes_ = -1;
};

}  // namespace sextant::engine
