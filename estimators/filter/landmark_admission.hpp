#pragma once
// EKF-SLAM's rule for a sighting of a landmark the state does not hold yet, shared by the planar and the 3-D EKF:
// in SLAM mode, a landmark with an id (>= 0) is added to the state (state augmentation, state_augmentation.hpp) while
// the state holds fewer than max_landmarks; otherwise the sighting is refused and says why.
#include "estimators/filter/kalman_update.hpp"

#include <cstddef>
#include <cstdint>
#include <utility>

namespace sextant::filter {

/// Calls `add()` and returns an accepted result (kNewLandmark) when the landmark may join the state; else returns
/// the refusal: kUnknownLandmark (not in SLAM mode, or no id) or kMapFull (`held` >= max_landmarks).
template <class Add>
UpdateResult admit_new_landmark(bool slam, int64_t id, std::size_t held, int max_landmarks, Add&& add) {
  UpdateResult out;
  if (!slam || id < 0) {
    out.reason = UpdateReason::kUnknownLandmark;
  } else if (static_cast<int>(held) >= max_landmarks) {
    out.reason = UpdateReason::kMapFull;
  } else {
    std::forward<Add>(add)();
    out.accepted = true;
    out.reason = UpdateReason::kNewLandmark;
  }
  return out;
}

}  // namespace sextant::filter
