#pragma once
// One body's planar EKF fed by several odometry sources, in robot_localization's vocabulary (its `odomN_config`
// mask, `_differential`, `_rejection_threshold` and `sensor_timeout`), on top of PlanarEkf (planar_ekf.hpp).
//
// How several sources of one body are fused: the state has no velocity, so exactly one source per body drives the
// prediction (`predict`: its pose increments and their covariance are the motion model, as with a single source);
// every other source is a measurement of the same motion:
//  - differential (default): the increment Z of the source's pose between two of its messages, fused against the
//    filter's motion over the same interval.  The filter keeps a clone of the robot pose taken at the source's
//    previous message (stochastic cloning, Roumeliotis & Burdick 2002), so Z = C^-1 X Exp(v) is an exact relative
//    measurement, correlated correctly with everything else (robot_localization instead turns the increment into a
//    velocity).  Noise: the message's increment covariance, or the difference of its pose covariances.
//  - absolute (`differential: false`): the source's pose itself, Z = F^-1 X Exp(v) with R its pose covariance; the
//    frame F of the source is anchored at its first message (F = X_hat Z_1^-1, which carries no information).
//  - velocities (vx, vy, vyaw in the mask): the message's twist integrated over the interval since the source's
//    previous message, Exp(v dt) with covariance Sigma_v dt^2 (mean of the two messages' twists and covariances),
//    fused as a relative measurement like a differential increment.  A source may not fuse both a differential
//    pose and velocities (the same motion twice).
// Components not in a source's mask are not fused (rows dropped from the measurement).  The rejection gate is a
// chi-square threshold on the normalized innovation of the fused components (0: none); rejected measurements are
// counted.  Timeout: a source silent for more than `timeout_s` (measured on the body's newest input stamp) is
// reported once and no longer fused; its first message afterwards re-anchors it (the gap's motion is not fused,
// robot_localization#871).  Measurement sources are applied at the state of the body's latest prediction (their
// stamps are not interpolated); landmark sightings can be placed between two predictions (the `stops` overload).
#include "estimators/filter/planar_ekf.hpp"

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sextant::filter {

struct OdometrySourceOptions {
  bool predict = false;  // drives the prediction (exactly one source of a body)
  std::array<bool, 6> fuse{true, true, true, false, false, false};  // x, y, yaw, vx, vy, vyaw
  bool differential = true;
  double gate = 0;       // chi-square threshold on the fused components' normalized innovation; 0 = no gate
  double timeout_s = 0;  // 0 = never
};

/// One planar odometry message: pose in the source's frame, covariances over [x, y, yaw] (right perturbation,
/// body frame) and an optional body-frame twist [vx, vy, vyaw].
struct PlanarOdometry {
  int64_t utime = 0;
  SE2 pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  std::optional<Eigen::Matrix3d> increment_covariance;  // since the source's previous message
  std::optional<Eigen::Vector3d> twist;
  Eigen::Matrix3d twist_covariance = Eigen::Matrix3d::Zero();
};

/// What happened to one odometry message.
enum class OdometryOutcome {
  initialized,   // first message of the predicting source: the body starts here
  predicted,     // predicting source
  fused,         // measurement source, accepted
  anchored,      // measurement source: first message, or first after a timeout (nothing to fuse yet)
  gated,         // rejected by the gate
  rejected,      // degenerate (non-finite, singular)
  duplicate,     // not newer than the source's previous message
  before_start,  // a measurement source before the predicting source's first message
  unknown_source,
};

struct SourceCounters {
  int64_t messages = 0, fused = 0, gated = 0, rejected = 0, timeouts = 0;
  bool silent = false;  // timed out and not heard from since
};

class MultiSourceEkf {
 public:
  MultiSourceEkf() = default;
  /// `sources` by name; exactly one must have `predict` (std::invalid_argument otherwise, also for a source that
  /// fuses nothing, or a differential pose together with velocities).
  MultiSourceEkf(const PlanarEkfOptions& options, const Eigen::Matrix3d& initial_covariance,
                 std::map<std::string, OdometrySourceOptions> sources, double min_increment_variance = 1e-10);

  /// Throws std::invalid_argument unless the sources make a valid body (the rules of the constructor).
  static void validate(const std::map<std::string, OdometrySourceOptions>& sources);

  OdometryOutcome odometry(const std::string& source, const PlanarOdometry& m);
  /// The same, for a message of the predicting source whose prediction passes through `stops` (utimes strictly
  /// between the previous prediction and m.utime, increasing): the increment Delta is split by interpolation on
  /// SE(2), Delta_a = Exp(a Log Delta) with a the fraction of the interval, its noise in proportion (a Q), and
  /// `at_stop(i)` runs with the state predicted to stops[i] (to apply sightings taken between two odometry
  /// messages at the pose they were taken from).  Stops outside the interval are skipped.
  OdometryOutcome odometry(const std::string& source, const PlanarOdometry& m, const std::vector<int64_t>& stops,
                           const std::function<void(size_t)>& at_stop);
  /// Advances the body's clock to `utime` (any input of the body does): sources silent for longer than their
  /// timeout are reported.
  void advance(int64_t utime);

  bool started() const { return started_; }
  int64_t utime() const { return utime_; }  // of the newest prediction
  PlanarEkf& ekf() { return ekf_; }
  const PlanarEkf& ekf() const { return ekf_; }
  const std::map<std::string, SourceCounters>& counters() const { return counters_; }

  /// The motion noise of an increment: the given increment covariance, or (differential fallback) the pose
  /// covariance minus the previous one carried through the motion, cov - Ad(delta^-1) cov_prev Ad(delta^-1)';
  /// symmetrized with eigenvalues at least `min_variance`.
  static Eigen::Matrix3d increment_noise(const PlanarOdometry& previous, const PlanarOdometry& current,
                                         double min_variance);

  /// The fusion's state (the EKF, each source's last message, clone and frame, the counters) in the binary archive;
  /// the options and the sources' settings are the constructor's (a saved source it does not have is an error).
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  struct Source {
    OdometrySourceOptions options;
    std::optional<PlanarOdometry> last;  // previous message (nullopt: not anchored)
    int64_t last_seen = 0;
    int clone = -1;  // index of the pose clone in the state (relative measurements)
    SE2 frame;       // absolute mode: the source's frame in the map
  };
  OdometryOutcome measure(Source& s, SourceCounters& c, const PlanarOdometry& m);

  PlanarEkfOptions options_;
  Eigen::Matrix3d initial_covariance_ = Eigen::Matrix3d::Identity();
  double min_variance_ = 1e-10;
  PlanarEkf ekf_;
  bool started_ = false;
  int64_t utime_ = 0, clock_ = 0;
  std::map<std::string, Source> sources_;
  std::map<std::string, SourceCounters> counters_;
};

}  // namespace sextant::filter
