#pragma once
// Plausibility by physics: the intake's second check, after decoding (every number finite, covariances positive
// definite, codec.hpp) and the time guard.  A message that is well-formed but physically impossible for the body that
// sent it is refused and counted by reason, before any estimator sees it:
//   implausible_position    a position, sensor position or loop translation beyond max_position_m;
//   implausible_range       a landmark sighting beyond max_range_m;
//   implausible_tilt        a planar message whose orientation has roll or pitch above max_planar_tilt_rad (below,
//                           the estimators project it onto the plane: x, y and yaw are kept);
//   implausible_covariance  a covariance (odometry pose, increment, twist; sighting; bearing sigmas; the inverse of a
//                           loop's information) whose meaningful block has an eigenvalue outside [min_variance,
//                           max_variance] or a condition number above max_condition;
//   implausible_rate, implausible_acceleration  an IMU sample beyond max_angular_rate_radps / max_acceleration_mps2
//                           (and its stated covariances as above); a GNSS velocity beyond the 3-D speed;
//   implausible_speed       an odometry position farther from the source's previous accepted one than
//                           speed * dt + max_jump_m (speed by the body's kind: planar or 3-D).
// A source whose odometry keeps "jumping" consistently — `resync_messages` refused messages in a row, each plausible
// from the one before it — was reset, not attacked: its next message is accepted as a fresh start and reported
// through `resynced()` (the daemon then has the stages forget the body, as for a clock re-synchronisation).
// Memory: one entry per odometry stream, at most `max_streams` (the least recently seen is forgotten first).
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/codec.hpp"

#include <map>
#include <optional>
#include <string>

namespace sextant::runtime {

class Plausibility {
 public:
  Plausibility(config::Plausibility limits, int resync_messages, size_t max_streams);

  /// nullopt when `event` (received on `stream`, the time guard's stream name) is plausible, else why not.
  std::optional<Rejection> check(const std::string& stream, const engine::Event& event);
  /// Whether the last accepted message re-started its stream after a consistent reset (see above).
  bool resynced() const { return resynced_; }
  /// Forgets a stream (its source went idle): its next message starts afresh.
  void forget(const std::string& stream) { motion_.erase(stream); }
  size_t streams() const { return motion_.size(); }

 private:
  struct Motion {
    int64_t utime = 0;
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    int refused_in_row = 0;  // consecutive implausible_speed refusals, each plausible from the previous one
    int64_t refused_utime = 0;
    Eigen::Vector3d refused_position = Eigen::Vector3d::Zero();
  };
  std::optional<Rejection> check_imu(const engine::ImuSample& m) const;
  std::optional<Rejection> check_gnss(const engine::GnssFix& g) const;
  std::optional<Rejection> check_odometry(const std::string& stream, const engine::Odometry& o);
  std::optional<Rejection> check_speed(const std::string& stream, const engine::Odometry& o);
  bool within_speed(int64_t from_utime, const Eigen::Vector3d& from, const engine::Odometry& o) const;

  config::Plausibility limits_;
  int resync_messages_;
  size_t max_streams_;
  std::map<std::string, Motion> motion_;
  bool resynced_ = false;
};

}  // namespace sextant::runtime
