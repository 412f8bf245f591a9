#pragma once
// Keyframe selection by motion magnitude (source B, "Graph-optimisation-based 3D visual odometry with Kinect").
//
// The motion from the last keyframe to the current odometry pose is the tangent vector
//     mu = Log(T_kf^-1 T) = [rho; phi]        (SE(3), translation first; or SE(2) [x, y; yaw] when planar)
// and its magnitude is
//     L = sqrt(w_t |rho|^2 + w_r |phi|^2)     (metres and radians, combined by the weights w_t, w_r).
// rho is the translational part of the logarithm (equal to the translation for a pure translation, the chord
// scaled by the rotation's V^-1 otherwise).  Decision:
//     L <  k1        kTooClose      not a keyframe (the reference stays)
//     k1 <= L <= k2  kKeyframe      a new keyframe: it becomes the reference
//     L >  k2        kImplausible   an implausible jump (a wrong odometry estimate): rejected, counted, the
//                                   reference stays
// The first pose is always a keyframe.  A pose with a non-finite component (or whose motion magnitude is not
// finite) is kImplausible and counted, and never becomes the reference.
// Source B's own run used k1 = 0.8, k2 = 2 in its units; sextant's defaults are for metres and radians.
#include "estimators/lie/se2.hpp"
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <optional>

namespace sextant {

struct KeyframeSelectorOptions {
  double k1 = 0.3;                  // smallest motion magnitude of a new keyframe
  double k2 = 5.0;                  // largest plausible motion magnitude
  double translation_weight = 1.0;  // w_t, per m^2
  double rotation_weight = 1.0;     // w_r, per rad^2
  bool planar = false;              // measure the motion in SE(2) (x, y, yaw of each pose; z, roll, pitch ignored)
};

enum class KeyframeDecision { kTooClose, kKeyframe, kImplausible };

const char* to_string(KeyframeDecision d);

class KeyframeSelector {
 public:
  /// Throws std::invalid_argument unless 0 <= k1 < k2 (finite) and both weights are finite, >= 0 and not both 0.
  explicit KeyframeSelector(const KeyframeSelectorOptions& options = {});

  /// Classifies the odometry pose `odometry_pose` (any fixed frame, the same for every call); on kKeyframe it
  /// becomes the reference of the next decisions.
  KeyframeDecision decide(const SE3& odometry_pose);

  /// L of the last decide() (0 for the first pose; NaN after a non-finite pose).
  double last_magnitude() const { return last_magnitude_; }
  /// The motion magnitude L between two poses with this selector's weights and planar setting.
  double magnitude(const SE3& from, const SE3& to) const;

  int64_t accepted() const { return accepted_; }  // keyframes, the first pose included
  int64_t rejected() const { return rejected_; }  // kImplausible decisions
  int64_t too_close() const { return too_close_; }
  /// The pose of the last keyframe (nullopt before the first one).
  const std::optional<SE3>& reference() const { return reference_; }
  const KeyframeSelectorOptions& options() const { return options_; }

 private:
  KeyframeSelectorOptions options_;
  std::optional<SE3> reference_;
  double last_magnitude_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, too_close_ = 0;
};

}  // namespace sextant
