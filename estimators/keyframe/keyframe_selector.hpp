#pragma once
// Keyframe selection by motion magnitude ("Graph-optimisation-based 3D visual odometry with Kinect",
// Sensors and Microsystems 2019).
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
// Re-anchoring (sextant's addition; the paper keeps the reference for good): a jump can be real — the odometry lost
// track and resumed somewhere else, or the body was carried — and then every later pose is implausible against the
// old reference and keyframing would stop forever.  A jump is taken as real when `reanchor_after` poses in a row are
// implausible *and* consistent with each other (each within k2 of the implausible pose before it, by the same L):
// the last of them becomes the reference and the decision is kReanchored (counted).  A spurious spike — one pose, or
// a few, off and then back — is still rejected; so is a run of wild poses that do not agree with each other (a
// pose farther than k2 from the previous implausible one starts a new run).  Any too-close or keyframe decision ends
// the run.  reanchor_after = 0 never re-anchors (the paper's behaviour).
// The first pose is always a keyframe.  A pose with a non-finite component (or whose motion magnitude is not
// finite) is kImplausible and counted, never becomes the reference and ends a run towards re-anchoring.
// The paper's own run used k1 = 0.8, k2 = 2 in its units; sextant's defaults are for metres and radians.
#include "estimators/archive/binary_archive.hpp"
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
  int reanchor_after = 10;          // consecutive, mutually consistent implausible poses that make the last one the
                                    // new reference (a real jump); 0: never
};

/// kReanchored: after a real jump (see above) the pose becomes the new reference, as a keyframe does; a graph should
/// link it across the jump with a weak edge (or start a new segment), not with the odometry's own covariance.
enum class KeyframeDecision { kTooClose, kKeyframe, kImplausible, kReanchored };

const char* to_string(KeyframeDecision d);

class KeyframeSelector {
 public:
  /// Throws std::invalid_argument unless 0 <= k1 < k2 (finite), both weights are finite, >= 0 and not both 0, and
  /// reanchor_after >= 0.
  explicit KeyframeSelector(const KeyframeSelectorOptions& options = {});

  /// Classifies the odometry pose `odometry_pose` (any fixed frame, the same for every call); on kKeyframe and
  /// kReanchored it becomes the reference of the next decisions.
  KeyframeDecision decide(const SE3& odometry_pose);

  /// L of the last decide() (0 for the first pose; NaN after a non-finite pose).
  double last_magnitude() const { return last_magnitude_; }
  /// The motion magnitude L between two poses with this selector's weights and planar setting.
  double magnitude(const SE3& from, const SE3& to) const;

  int64_t accepted() const { return accepted_; }  // keyframes, the first pose included
  int64_t rejected() const { return rejected_; }  // kImplausible decisions
  int64_t too_close() const { return too_close_; }
  int64_t reanchored() const { return reanchored_; }  // kReanchored decisions
  /// Implausible poses in the current run towards re-anchoring (0 when the last decision was not kImplausible).
  int jump_run() const { return jump_run_; }
  /// The pose of the last keyframe (nullopt before the first one).
  const std::optional<SE3>& reference() const { return reference_; }
  /// Makes `pose` the reference (nullopt: none, the next pose will be the first keyframe) and ends any run towards
  /// re-anchoring; the counters stay as they are.  For a caller that could not use the keyframe (or re-anchoring)
  /// this selector has just accepted and goes back to the last keyframe it did use: the graph stage drops a keyframe
  /// whose odometry edge covariance it cannot invert, and the next keyframe must then be measured from — and its
  /// odometry edge span from — a pose that is in the graph, not from the dropped one (with k2 = 5 and a dropped
  /// keyframe 4.9 m out, a pose 5.3 m from the graph's last keyframe would otherwise pass as 0.4 m of motion).
  /// Throws std::invalid_argument for a pose with a non-finite component.
  void reset_reference(const std::optional<SE3>& pose);
  const KeyframeSelectorOptions& options() const { return options_; }
  /// The decision state (reference, run towards re-anchoring, counters) in the binary archive; the options are the
  /// constructor's (load keeps this selector's own).
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  KeyframeSelectorOptions options_;
  std::optional<SE3> reference_;
  std::optional<SE3> jump_last_;  // the last implausible pose of the current run
  int jump_run_ = 0;
  double last_magnitude_ = 0;
  int64_t accepted_ = 0, rejected_ = 0, too_close_ = 0, reanchored_ = 0;
};

}  // namespace sextant
