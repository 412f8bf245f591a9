#pragma once
// A trajectory sampled at discrete stamps, evaluated at any time inside its span by interpolating between the two
// nearest stamps t0 <= t <= t1 with s = (t - t0) / (t1 - t0):
//     position = (1 - s) p0 + s p1,   orientation = slerp(q0, q1, s)  (the shorter arc)
// Exact at the stamps; no extrapolation: a time outside [first stamp, last stamp] has no pose.
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace sextant::tools {

class InterpolatedTrajectory {
 public:
  InterpolatedTrajectory() = default;
  /// Samples (utime in microseconds, pose) in any order.  Sorted by time; of several samples with one stamp the
  /// first is kept; samples with a non-finite component are dropped (count in dropped()).
  explicit InterpolatedTrajectory(std::vector<std::pair<int64_t, SE3>> samples);

  /// The interpolated pose at `utime`, nullopt outside the span (or when empty).
  std::optional<SE3> at(int64_t utime) const;

  bool empty() const { return samples_.empty(); }
  size_t size() const { return samples_.size(); }
  int64_t first_utime() const { return samples_.empty() ? 0 : samples_.front().first; }
  int64_t last_utime() const { return samples_.empty() ? 0 : samples_.back().first; }
  int64_t dropped() const { return dropped_; }
  const std::vector<std::pair<int64_t, SE3>>& samples() const { return samples_; }

 private:
  std::vector<std::pair<int64_t, SE3>> samples_;
  int64_t dropped_ = 0;
};

}  // namespace sextant::tools
