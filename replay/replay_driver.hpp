#pragma once
// Deterministic replay: an LCM log through the same intake, engine and publisher as sextantd, synchronously, in
// message utime order (not the log's wall-clock stamps: lcm-logger stamps receive time).  Ties keep file order.
// The same log and config give the same published bytes on every run.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace sextant::tools {

struct PublishedMessage {
  std::string channel;
  int64_t utime = 0;
  std::vector<uint8_t> bytes;
};

/// A ground-truth pose read from the log's GROUND_TRUTH channel (truth_t, kind "robot").
struct TruthPose {
  int64_t utime = 0;
  std::string source;
  engine::Pose pose;
};

/// A ground-truth point (truth_t, kind "target" or "landmark").
struct TruthPoint {
  int64_t utime = 0;
  std::string kind;
  int64_t id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

struct StageReport {
  std::string name;
  int64_t processed = 0;
  engine::Counters counters;
  /// Per event processing time (wall clock; not part of the deterministic outputs): every event, or with
  /// ReplayOptions::max_kept an evenly spaced sample of them (the max is latency_max_ms).
  std::vector<double> latency_ms;
  double latency_max_ms = 0;
  /// Events whose handling threw (the replay goes on, as the daemon does: engine/guarded_handle.hpp), how many of
  /// them the stage recovered from, and what the last one said.  Also in `counters` as stage_failures/_recoveries.
  int64_t failures = 0, recoveries = 0;
  std::string last_failure;
};

/// What a replay keeps in memory and where it streams the rest.
struct ReplayOptions {
  /// Series kept in ReplayResult (each estimator's fused poses, truth poses, stage latencies) hold at most this many
  /// entries: beyond it every other entry is dropped and only every 2nd, 4th, ... is kept from then on (an evenly
  /// spaced sample, the same on every run); targets keep the newest 64, trajectories and match requests none,
  /// published bytes none (stream them with on_publish).  0: everything, as small logs and tests want.
  size_t max_kept = 0;
  /// Every published message, as the bus would carry it (channel, encoded bytes, utime), in publish order.
  std::function<void(const std::string&, const std::vector<uint8_t>&, int64_t)> on_publish;
  /// Every fused pose, in publish order (for writing a trajectory file as the replay goes).
  std::function<void(const engine::FusedPose&)> on_fused_pose;
  /// Every engine output, in publish order.
  std::function<void(const engine::Output&)> on_output;
  /// > 0: ReplayResult::segments reports each consecutive stretch of this many seconds of data time.
  double segment_seconds = 0;
  /// The graph's stages on a second thread beside the others (runtime::StageLanes::kPipelined): the same outputs in
  /// the same order as on one thread (false), sooner on two cores.
  bool pipelined = true;
};

/// One stretch of a replay (ReplayOptions::segment_seconds of data time): how fast it replayed and how long the
/// stages took per event in it, and the process's resident memory at its end — cost against run length.
struct SegmentReport {
  double start_s = 0, data_s = 0;  // data time from the first event, and the stretch's length
  double wall_s = 0;               // wall-clock time spent replaying it
  int64_t rss_kb = 0;              // resident set size at its end (0 where /proc is not available)
  struct Stage {
    std::string name;
    int64_t events = 0;
    double p50_ms = 0, p99_ms = 0, max_ms = 0;  // processing time per event (percentiles: nearest rank)
  };
  std::vector<Stage> stages;
  engine::Counters graph_counters;  // the graph stage's counters at its end (graph size), empty without one
};

struct ReplayResult {
  std::string primary_estimator;
  int64_t records = 0;            // log events read
  runtime::LogDamage log_damage;  // corrupt events the reader skipped (resynchronising on the next one)
  int64_t first_utime = 0, last_utime = 0;
  std::map<std::string, runtime::ChannelCounts> channels;             // per input channel
  std::vector<PublishedMessage> published;                            // in publish order
  std::map<std::string, int64_t> published_counts;                    // per output channel
  std::map<std::string, std::vector<engine::FusedPose>> fused_poses;  // by estimator
  std::vector<engine::Trajectory> trajectories;
  std::vector<engine::Targets> targets;
  std::vector<engine::MatchRequest> match_requests;
  std::vector<engine::LandmarkMap> landmark_maps;
  std::vector<TruthPose> truth_poses;
  std::vector<TruthPoint> truth_points;
  std::vector<StageReport> stages;
  double wall_seconds = 0;
  // Totals (what the series above hold may be a sample or nothing: ReplayOptions::max_kept).
  std::map<std::string, int64_t> fused_pose_counts;           // by estimator
  std::map<std::string, engine::FusedPose> last_fused_poses;  // by estimator
  std::map<std::string, engine::GeoPose> last_geo_poses;      // by "<source>/<estimator>"
  int64_t geo_pose_messages = 0;
  int64_t trajectory_messages = 0, target_messages = 0, match_request_messages = 0, landmark_map_messages = 0;
  int64_t fleet_messages = 0;           // FLEET and FLEET_CONTROL (engine.graph.fleet.exchange)
  std::vector<SegmentReport> segments;  // ReplayOptions::segment_seconds
};

/// Called every few thousand events with (events done, events total).
using Progress = std::function<void(int64_t, int64_t)>;

/// Replays `log_path` through the engine configured by `config`.  Throws std::runtime_error when the log cannot
/// be read.
/// The log is read twice (once for the utime of every record, once to feed them; see TimeOrderedLog), so memory holds
/// an index of 4 bytes per record and at most TimeOrderedLog::kHeldBytes of records that arrive ahead of their turn,
/// not the log.
ReplayResult replay_log(const std::string& log_path, const config::DaemonConfig& config, const Progress& progress = {},
                        const ReplayOptions& options = {});

}  // namespace sextant::tools
