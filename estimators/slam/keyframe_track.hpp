#pragma once
// The keyframe track of one body: its keyframes in the graph (with the odometry between them), the keyframes lifelong
// thinning took out (their times and odometry poses), and a bounded history of its odometry poses; and what those
// answer: where a time of the body lands on a keyframe of the graph (time resolution for loops, anchoring for
// sightings) and the odometry's covariance along the path between two keyframes (the loop gate's).
//
// Time resolution (resolve): a loop end given by keyframe id at that keyframe's time is that keyframe; otherwise the
// nearest keyframe in time within the tolerance, moved to the exact time through the recorded odometry,
//     D = O_kf^-1 O_t        (O the odometry poses; the loop z becomes D_from z D_to^-1 between the keyframes),
// with zero covariance (the odometry bridges a short gap exactly enough); a time whose keyframes were thinned lands on
// the keyframe of the graph before it, with the covariance of the whole composed edge to the next keyframe of the
// graph as D's covariance (it contains D: an upper bound, so such a loop is weakened, not bent).
//
// Sighting anchors (anchor_at): the newest keyframe K at or before the time, D = O_K^-1 O_t with O_t interpolated on
// the group between the two odometry poses around t, O_t = O_0 Exp(a Log(O_0^-1 O_1)), a = (t - t_0) / (t_1 - t_0),
// and as D's covariance the odometry's from K to the next keyframe (or to the latest odometry): it contains the motion
// to the sighting and a little more.
#include "estimators/archive/binary_archive.hpp"
#include "estimators/keyframe/keyframe_thinning.hpp"
#include "estimators/lie/lie_archive.hpp"
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <map>
#include <optional>
#include <utility>
#include <vector>

namespace sextant::slam {

/// A keyframe of the graph.
struct TrackKeyframe {
  int64_t id = 0;  // the body's keyframe id: 0, 1, 2, ... in order of creation
  int64_t utime = 0;
  int variable = -1;                            // its pose variable in the smoother
  SE3 odom;                                     // the odometry pose at its time
  Matrix6d odom_covariance = Matrix6d::Zero();  // that pose's covariance as the odometry stated it
  Matrix6d edge_covariance = Matrix6d::Zero();  // of the odometry from the previous keyframe of the graph
  SE3 edge;                                     // that odometry (composed across thinned keyframes)
};

/// A keyframe that lifelong thinning took out of the graph: what resolving a time to it needs, and its place (at
/// the estimate it had when it was thinned), by which the records are bounded.
struct ThinnedKeyframe {
  int64_t id = 0, utime = 0;
  SE3 odom;
  KeyframePlace place{};
};

/// Where a time of the body lands: a keyframe of the graph (its position in keyframes()), the odometry motion D from
/// it to the time, and D's covariance (zero when D is taken as exact).
struct TrackPoint {
  size_t keyframe = 0;
  SE3 motion;
  Matrix6d covariance = Matrix6d::Zero();
};

class KeyframeTrack {
 public:
  /// Thinned records kept per place (of the grid lifelong thinning keeps one keyframe per): the newest visits of each
  /// place stay resolvable, older ones are forgotten, so the records follow the explored space, not the run's length.
  /// Loops to old visits matter: in the 8-robot simulated hour (bench/fleet_lifelong.sh), keeping only 4 per place
  /// left 3,800 more loops unmatched and two robots' fleet-frame ATE 0.013 -> 0.025 and 0.020 -> 0.024 m.  256 keep
  /// that hour's records whole (112 bytes each: at most 28 KB per place and body).  The bound is enforced when the
  /// records have grown by a quarter since it last was, so a place may briefly hold up to a quarter more.
  static constexpr size_t kThinnedRecordsPerPlace = 256;

  const std::vector<TrackKeyframe>& keyframes() const { return keyframes_; }
  bool empty() const { return keyframes_.empty(); }
  const TrackKeyframe& newest() const { return keyframes_.back(); }
  const std::vector<ThinnedKeyframe>& thinned() const { return thinned_; }
  const std::vector<std::pair<int64_t, SE3>>& odometry() const { return odometry_; }

  /// The latest odometry message: its time, pose and pose covariance (time 0 before the first).
  int64_t last_utime() const { return last_utime_; }
  const SE3& last_odom() const { return last_odom_; }
  const Matrix6d& last_odom_covariance() const { return last_odom_covariance_; }
  /// The covariance of the odometry since the newest keyframe (composed message by message).
  const Matrix6d& since_keyframe() const { return since_keyframe_; }

  /// The motion `delta` from the previous odometry message to a new one, with covariance `q`, composed onto
  /// since_keyframe() (compose_covariance, estimators/lie/pose_covariance.hpp).
  void extend_since_keyframe(const SE3& delta, const Matrix6d& q);
  /// A new odometry message: the latest pose and covariance, and the pose enters the history (at most `history`
  /// poses: when it is full the older half goes).
  void advance(int64_t utime, const SE3& pose, const Matrix6d& pose_covariance, size_t history);

  /// Appends a keyframe and restarts since_keyframe(); returns its id: the keyframe's own when it is not below
  /// next_id() (a remote body's keyframes keep their owner's ids), else the next one.
  int64_t add_keyframe(TrackKeyframe keyframe);
  /// The id the next keyframe gets.
  int64_t next_id() const { return next_keyframe_id_; }
  /// Replaces the keyframes of the graph after thinning (oldest first, variables renumbered) and adds the records of
  /// the thinned ones (kept in time order; per place the newest kThinnedRecordsPerPlace stay).
  void replace_keyframes(std::vector<TrackKeyframe> keyframes, const std::vector<ThinnedKeyframe>& thinned);
  /// Renumbers the keyframes' variables (remap[old] = new).
  void remap_variables(const std::vector<int>& remap);

  /// A time of the body on a keyframe of the graph (see above): by `keyframe_id` when it names a keyframe at exactly
  /// `utime`, else the nearest keyframe within `tolerance_us`, else through thinned keyframes; nullopt when the time
  /// cannot be tied (no odometry pose recorded at it, outside the graph's keyframes, or after the newest keyframe and
  /// farther than the tolerance).
  std::optional<TrackPoint> resolve(int64_t keyframe_id, int64_t utime, int64_t tolerance_us) const;
  /// The position in keyframes() of the keyframe with this id (nullopt: not in the graph).
  std::optional<size_t> position_of(int64_t id) const;
  /// The keyframe position of the newest keyframe at or before `utime` (nullopt: none).
  std::optional<size_t> keyframe_at_or_before(int64_t utime) const;
  /// A sighting's anchor at `utime` (see above): requires a keyframe at or before it and utime <= last_utime();
  /// nullopt when the odometry history no longer holds poses around it.
  std::optional<TrackPoint> anchor_at(int64_t utime) const;
  /// The composed odometry motion from keyframe `from` to keyframe `to` (positions; either order) and its covariance
  /// in `from`'s frame: edges composed from the older to the newer, then for a backward path the covariance of the
  /// inverse motion, Ad(X) P Ad(X)' with X the forward motion.
  std::pair<SE3, Matrix6d> odometry_path(size_t from, size_t to) const;

  /// The track in the binary archive: odometry state, keyframes, thinned records, next id and history.
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  // Of each place's records, all but the newest kThinnedRecordsPerPlace go (the order of the rest stays).
  void forget_old_visits();
  size_t thinned_bounded_ = 0;  // records after the last forget_old_visits()

  int64_t last_utime_ = 0;
  SE3 last_odom_;
  Matrix6d last_odom_covariance_ = Matrix6d::Zero();
  Matrix6d since_keyframe_ = Matrix6d::Zero();
  std::vector<TrackKeyframe> keyframes_;  // in the graph, by id (and time)
  std::map<int64_t, size_t> by_utime_;    // -> position in keyframes_
  std::vector<ThinnedKeyframe> thinned_;  // taken out by lifelong thinning, in time order; the newest
                                          // kThinnedRecordsPerPlace per place
  int64_t next_keyframe_id_ = 0;
  std::vector<std::pair<int64_t, SE3>> odometry_;  // recent odometry poses (bounded)
};

}  // namespace sextant::slam
