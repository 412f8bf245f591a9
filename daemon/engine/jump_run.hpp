#pragma once
// The re-synchronisation rule for a value that should move steadily (a stream's clock, the association's scan ids):
// a value far from the recent ones is refused without moving them, since one wrong value (a stamp dated 2100, a scan
// id of INT64_MAX) must not cut off everything after it; but a run of `resync_after` consecutive refused values that
// agree with each other (each after the previous one, or equal to it when `allow_equal`, and within `window` of it)
// means the source truly jumped (a robot restarted with another clock, a sensor network that renumbered its scans):
// the last of the run is taken, and the caller moves to it.  Used by the input side's time guard
// (daemon/runtime/time_order_guard.hpp) and by the association stage; each decides what "far" is.
#include <algorithm>
#include <cstdint>

namespace sextant::engine {

/// |a - b| without signed overflow.
inline uint64_t value_distance(int64_t a, int64_t b) {
  return a >= b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

class JumpRun {
 public:
  /// A value the caller refused as far from its clock.  True when it completes a run of consistent refused values:
  /// the caller re-synchronises on it (the run starts over).
  bool refused(int64_t value, uint64_t window, int resync_after, bool allow_equal = false) {
    const bool consistent =
        count_ > 0 && (value > last_ || (allow_equal && value == last_)) && value_distance(value, last_) <= window;
    count_ = consistent ? count_ + 1 : 1;
    last_ = value;
    if (count_ < std::max(resync_after, 1)) return false;
    count_ = 0;
    return true;
  }
  /// A value the caller accepted: a run of refused ones is broken.
  void accepted() { count_ = 0; }
  /// Consecutive consistent refused values so far.
  int count() const { return count_; }

 private:
  int64_t last_ = 0;
  int count_ = 0;
};

}  // namespace sextant::engine
