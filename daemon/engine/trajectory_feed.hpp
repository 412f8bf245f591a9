#pragma once
// What TRAJECTORY carries for one body, so that a subscriber can rebuild the body's current trajectory from small,
// rate-limited messages (lcmtypes/sextant/trajectory_t.lcm states the rebuild rule).  At each publication (at most
// `rate_hz` per second of data time, so a replay publishes what the daemon would):
//   1. UPDATE: the keyframes that are new or moved past the thresholds since they were last published, new ones first
//      (by id), then the largest moves, at most `max_keyframes_per_tick`; the rest wait for the next publication.
//      Keyframes that left the trajectory are listed in removed_ids.
//   2. SNAPSHOT: the next `snapshot_chunk` keyframes (by id) of a rolling snapshot, with their current poses; the
//      chunk is authoritative for its id range, so a late subscriber (or one that lost a datagram) converges within
//      one cycle.
// Messages carry at most `max_keyframes_per_message` keyframes each (72 bytes apiece on the wire).  flush() sends
// every keyframe that differs at all from what was published, however many: the end of a replay or a shutdown.
// The cost of a publication is one pass over the body's keyframes; between publications there is none.
#include "daemon/engine/outputs.hpp"
#include "estimators/archive/binary_archive.hpp"

#include <cstdint>
#include <map>
#include <vector>

namespace sextant::engine {

struct TrajectoryFeedOptions {
  double rate_hz = 1.0;                 // publications per second of data time; 0: after every graph update
  double move_translation = 0.01;       // m: a keyframe that moved more than this since it was published is sent again
  double move_rotation = 0.005;         // rad: ... or turned more than this
  int max_keyframes_per_message = 512;  // ~37 KB per message
  int max_keyframes_per_tick = 1024;    // UPDATE keyframes per publication (new and moved); the rest wait
  /// Keyframes of the rolling snapshot per publication; 0: no snapshot.  The snapshot is most of the traffic of a
  /// steady trajectory (64: 4.6 KB per publication; 256 made 15.6 KB/s on the planar 60-minute run, 92 % of it the
  /// snapshot); a late subscriber has the whole trajectory after keyframes / snapshot_chunk publications.
  int snapshot_chunk = 64;
};

class TrajectoryFeed {
 public:
  explicit TrajectoryFeed(TrajectoryFeedOptions options = {}) : options_(options) {}

  /// True when a publication is due at data time `utime` (microseconds).
  bool due(int64_t utime) const { return !started_ || utime >= next_utime_; }

  /// The messages of one publication at `utime`, given the body's current keyframes in increasing id order and the
  /// header (chi2, iterations, solve time, source) to copy into each.  `flush`: every keyframe that differs from what
  /// was published, no budget, no snapshot chunk.
  std::vector<Trajectory> publish(int64_t utime, const std::vector<Keyframe>& current, const Trajectory& header,
                                  bool flush = false);

  const TrajectoryFeedOptions& options() const { return options_; }
  /// What has been published and where the snapshot is (the options are the constructor's).
  void save(archive::ArchiveWriter& w) const;
  void load(archive::ArchiveReader& r);

 private:
  // publish's steps (trajectory_feed.cpp).
  struct Changes;
  Changes compare_with_published(const std::vector<Keyframe>& current, bool flush);
  std::vector<size_t> choose_keyframes_to_send(const Changes& changes, bool flush) const;
  void add_updates(std::vector<Trajectory>& out, const Trajectory& first, const std::vector<Keyframe>& current,
                   const std::vector<size_t>& send, const std::vector<int64_t>& removed);
  void add_snapshot_chunk(std::vector<Trajectory>& out, const Trajectory& first, const std::vector<Keyframe>& current);

  TrajectoryFeedOptions options_;
  bool started_ = false;
  int64_t next_utime_ = 0;
  std::map<int64_t, Pose> published_;  // by keyframe id: the pose last sent
  // The rolling snapshot: the next id to send, its cycle and the cycle's chunk count.
  int64_t snapshot_cursor_ = 0, snapshot_id_ = 0;
  int snapshot_next_chunk_ = 0, snapshot_chunks_ = 0;
};

}  // namespace sextant::engine
