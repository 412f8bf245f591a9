#pragma once
// EKF-SLAM's rule for a sighting of a landmark the state does not hold yet, shared by the planar and the 3-D EKF:
// in SLAM mode, a landmark with an id (>= 0) is added to the state (state augmentation, state_augmentation.hpp) while
// the state holds fewer than max_landmarks; otherwise the sighting is refused and says why.
#include "estimators/filter/estimate_health.hpp"
#include "estimators/filter/kalman_update.hpp"

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

namespace sextant::filter {

/// Calls `add()` and returns an accepted result (kNewLandmark) when the landmark may join the state; else returns
/// the refusal: kUnknownLandmark (not in SLAM mode, or no id) or kMapFull (`held` >= max_landmarks).  An `add` that
/// returns a Health (estimate_health.hpp) may refuse too: it left the state as it was, the reason is kNonFinite or
/// kIndefinite.
template <class Add>
UpdateResult admit_new_landmark(bool slam, int64_t id, std::size_t held, int max_landmarks, Add&& add) {
  UpdateResult out;
  if (!slam || id < 0) {
    out.reason = UpdateReason::kUnknownLandmark;
  } else if (static_cast<int>(held) >= max_landmarks) {
    out.reason = UpdateReason::kMapFull;
  } else {
    if constexpr (std::is_same_v<decltype(std::forward<Add>(add)()), Health>) {
      const Health h = std::forward<Add>(add)();
      if (h != Health::kHealthy) {
        out.reason = h == Health::kNonFinite ? UpdateReason::kNonFinite : UpdateReason::kIndefinite;
        return out;
      }
    } else {
      std::forward<Add>(add)();
    }
    out.accepted = true;
    out.reason = UpdateReason::kNewLandmark;
  }
  return out;
}

}  // namespace sextant::filter
