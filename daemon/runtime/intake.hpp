#pragma once
// The input side shared by sextantd and `sextant replay`: raw bytes on a known channel -> a validated event, or a
// counted rejection.  One instance per input stream; not thread-safe (the daemon calls it from its LCM thread,
// replay from its loop).  Nothing it is given can make it throw: an unexpected exception is a rejection
// ("internal") like any other.
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/plausibility.hpp"
#include "daemon/runtime/source_claims.hpp"
#include "daemon/runtime/sequence_gaps.hpp"
#include "daemon/runtime/time_order_guard.hpp"

#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>

namespace sextant::runtime {

/// When a message arrived.  Live: the bus's clocks (the monotonic one for idle expiry and the slack of a paused
/// sender, the wall clock for far-future stamps).  Replay: the log's time on both, so that what the intake decides
/// depends on the data alone, never on how fast the replay runs.
struct Arrival {
  std::chrono::steady_clock::time_point steady;
  int64_t wall_utime = 0;
  /// Now, by the machine's clocks (a live daemon).
  static Arrival now();
  /// At a log time (microseconds): replay.
  static Arrival at_log_time(int64_t utime);
};

struct IntakeOptions {
  TimeGuardOptions time;  // time_order_guard.hpp (its max_streams bounds bodies and sensors, idle_s expires them)
  bool live = false;      // check stamps against the wall clock too (sextantd; not replay)
  config::Plausibility plausibility;  // plausibility.hpp: bounds by physics, after the time guard
  double source_handover_s = 2.0;     // source_claims.hpp: a second sender of a stream waits this long for the first
};

/// The intake options of a daemon config (daemon.max_ahead_s, time_resync_messages, ...).
IntakeOptions intake_options(const config::DaemonConfig& config, bool live);

class Intake {
 public:
  /// `on_reject(channel, reason, message)` is told about every rejection (for rate-limited logging).
  using RejectHook = std::function<void(const std::string&, const std::string&, const std::string&)>;

  explicit Intake(ChannelStats& stats, RejectHook on_reject = {}, IntakeOptions options = {});

  void add_channel(const std::string& channel, InputKind kind);
  const std::map<std::string, InputKind>& channels() const { return channels_; }

  /// Decodes, validates, time-checks and plausibility-checks one message that arrived at `arrival`; nullopt when it
  /// was rejected (and counted).
  std::optional<engine::Event> accept(const std::string& channel, const void* data, size_t size, Arrival arrival);

  /// The body (odometry source) whose clock the last accepted message re-synchronised, empty when it did not: the
  /// daemon has every stage forget that body just before this message (its state belongs to the old clock).
  const std::string& resynced_body() const { return resynced_body_; }
  /// Streams whose clock jumped and was re-synchronised, and the last such event's description.
  int64_t time_resyncs() const { return order_.resyncs(); }
  const std::string& last_resync() const { return order_.last_resync(); }
  /// Bodies and sensors tracked now, and those forgotten (after idling, or evicted from a full table: both are
  /// counted as expired, the evicted ones also on their own).
  size_t sources() const { return order_.streams(); }
  int64_t sources_expired() const { return order_.expired(); }
  int64_t sources_evicted() const { return order_.evicted(); }
  /// Messages refused because another sender holds their stream (source_claims.hpp).
  int64_t source_claimed() const { return claims_.refused(); }
  /// The bodies whose odometry stream was forgotten after idling since the last call (their odometry source names):
  /// the daemon has the stages forget them too (Stage::forget), so that expiry frees all their per-body state.
  std::vector<std::string> take_expired_bodies();

 private:
  std::optional<engine::Event> accept_unguarded(const std::string& channel, InputKind kind, const void* data,
                                                size_t size, Arrival arrival);
  void reject(const std::string& channel, const std::string& reason, const std::string& message);

  ChannelStats& stats_;
  RejectHook on_reject_;
  IntakeOptions options_;
  std::map<std::string, InputKind> channels_;
  TimeOrderGuard order_;
  Plausibility plausible_;
  SourceClaims claims_;
  std::map<std::string, SequenceGaps> sequences_;  // per channel
  std::string resynced_body_;
};

}  // namespace sextant::runtime
