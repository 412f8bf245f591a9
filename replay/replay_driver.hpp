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

namespace sextant::replay {

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
  std::vector<double> latency_ms;  // per event processing time (wall clock; not part of the deterministic outputs)
};

struct ReplayResult {
  std::string primary_estimator;
  int64_t records = 0;                 // log events read
  runtime::LogDamage log_damage;       // corrupt events the reader skipped (resynchronising on the next one)
  int64_t first_utime = 0, last_utime = 0;
  std::map<std::string, runtime::ChannelCounts> channels;  // per input channel
  std::vector<PublishedMessage> published;                 // in publish order
  std::map<std::string, int64_t> published_counts;         // per output channel
  std::map<std::string, std::vector<engine::FusedPose>> fused_poses;  // by estimator
  std::vector<engine::Trajectory> trajectories;
  std::vector<engine::Targets> targets;
  std::vector<engine::MatchRequest> match_requests;
  std::vector<TruthPose> truth_poses;
  std::vector<TruthPoint> truth_points;
  std::vector<StageReport> stages;
  double wall_seconds = 0;
};

/// Called every few thousand events with (events done, events total).
using Progress = std::function<void(int64_t, int64_t)>;

/// Replays `log_path` through the engine configured by `config`.  Throws std::runtime_error when the log cannot
/// be read.
ReplayResult replay_log(const std::string& log_path, const config::DaemonConfig& config, const Progress& progress = {});

/// The utime of an encoded sextant message: every sextant type starts with `int64_t utime` right after LCM's 8-byte
/// fingerprint.  nullopt when the buffer is too short.
std::optional<int64_t> peek_utime(const std::vector<uint8_t>& bytes);

}  // namespace sextant::replay
