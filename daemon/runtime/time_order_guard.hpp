#pragma once
// The time guard of the input side: per stream (a channel and a body, or a bearing sensor) it keeps the stream's
// recent clock and refuses what would corrupt it.
//  - Backwards and duplicate stamps: odometry and bearing scans must strictly increase per stream; landmarks and
//    loop closures may arrive late (the stages place them) but an exact repeat of one of the stream's last 16 is a
//    duplicate.  Reason "time_order".
//  - Far-future stamps (live only, when the caller passes the clocks): more than `max_ahead_of_wall_s` ahead of the
//    wall clock, or ahead of the stream's clock by more than `max_ahead_s` plus the real time elapsed since that
//    clock last moved (a sender that paused for a minute may resume a minute later; a stamp cannot run ahead of real
//    time by more than `max_ahead_s` in one step), are refused without moving the clock.  Reason "time_future".
//    One odometry message dated 2100 used to move the clock and cut its body off until restart.  Replay needs no
//    such check: it feeds messages in utime order, so a far-future stamp comes last.
//  - True jumps: a stream whose clock really jumped (a robot restarted with another clock, a simulator reset) sends
//    `resync_after` consecutive messages that agree with each other (strictly increasing, each within `max_ahead_s`
//    of the one before) but not with the clock: the last of them is accepted and becomes the clock ("resync",
//    counted in `resyncs`).  Forward and backward jumps alike.
//  - Bounded state: at most `max_streams` streams; a new stream beyond that is refused (reason "too_many_sources")
//    and known streams are not slowed.  With `idle_s` > 0 a stream silent for that long (by the caller's monotonic
//    clock) is forgotten, which frees its place.  Live, a full table also makes room by eviction: a new stream takes
//    the place of the stream that sent the fewest messages among those silent for at least `evict_idle_s` (the
//    longest silent of them on a tie), so a flood of one-off names cannot lock a real body out for longer than that,
//    and a real body that merely paused is the last to go.  Replay never evicts, and its idle expiry goes by the
//    log's time (its answers must not depend on how fast it runs).
#include "daemon/engine/jump_run.hpp"

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace sextant::runtime {

struct TimeGuardOptions {
  double max_ahead_s = 60.0;          // live: further ahead of its stream's clock (beyond real time) is refused
  int resync_after = 5;               // consecutive consistent messages that move a jumped clock
  double max_ahead_of_wall_s = 60.0;  // live only: a message further ahead of the wall clock is refused
  int max_streams = 256;              // bodies and sensors tracked (per input side)
  double idle_s = 0;                  // forget a stream silent this long (0: never; the stages keep their state)
  double evict_idle_s = 60.0;         // live, table full: a stream silent this long may give its place (0: never)
};

class TimeOrderGuard {
 public:
  struct Refusal {
    std::string reason;  // "time_order", "time_future", "too_many_sources"
    std::string message;
  };
  using SteadyTime = std::chrono::steady_clock::time_point;
  /// The clocks of a live run: the wall clock (microseconds since the epoch) and the monotonic one.
  struct LiveClock {
    int64_t wall_utime = 0;
    SteadyTime now{};
  };

  explicit TimeOrderGuard(TimeGuardOptions options = {}) : options_(options) {}

  /// nullopt when `utime` is acceptable for `stream` (and records it), else why not.  `signature` tells apart
  /// messages of one stream that may share a stamp (a loop closure's from/to); `live` gives the clocks of a live
  /// run; in replay (nullopt) there is no far-future check and no eviction, and idle expiry goes by `replay_now`, the
  /// log's time as the caller maps it onto the steady clock's type, so that replay answers do not depend on how fast
  /// the replay runs.
  std::optional<Refusal> check(const std::string& stream, int64_t utime, bool strictly_increasing,
                               uint64_t signature = 0, std::optional<LiveClock> live = std::nullopt,
                               SteadyTime replay_now = SteadyTime{});

  int64_t resyncs() const { return resyncs_; }
  /// Streams forgotten: after idling (`idle_s`) or evicted from a full table (also counted in `evicted()`).
  int64_t expired() const { return expired_; }
  int64_t evicted() const { return evicted_; }
  /// The streams forgotten since the last call, for the caller to free what it keeps per stream.  Every one is
  /// kept up to 2 x max_streams between calls (a check forgets at most the max_streams tracked, by one sweep of idle
  /// ones and one eviction, and the daemon takes them after every message); beyond that, when the caller does not
  /// take them (replay, whose stages forget nothing), the oldest are let go and counted in `expired_untold`.
  std::vector<std::string> take_expired() { return std::exchange(expired_names_, {}); }
  int64_t expired_untold() const { return expired_untold_; }
  size_t streams() const { return streams_.size(); }
  /// The message of the last re-synchronisation (for the log), empty before the first.
  const std::string& last_resync() const { return last_resync_; }

 private:
  struct Stream {
    int64_t clock = 0;            // newest accepted utime
    engine::JumpRun jump;         // consecutive consistent refused stamps: a possible true jump
    std::deque<uint64_t> recent;  // signatures of the last accepted messages (duplicates)
    SteadyTime seen{};            // last message of any kind (idle expiry)
    SteadyTime moved{};           // when `clock` last moved
    int64_t messages = 0;         // messages seen (the eviction prefers the streams that said least)
  };
  void expire(SteadyTime now);
  void forget(std::unordered_map<std::string, Stream>::iterator it);
  // Lets go of the oldest names not taken beyond 2 x max_streams (counted in expired_untold_).
  void trim_expired();
  /// Live, table full: frees the place of the quietest stream silent for `evict_idle_s`; false when none is.
  bool evict(SteadyTime now);

  TimeGuardOptions options_;
  std::unordered_map<std::string, Stream> streams_;
  SteadyTime last_expiry_{};
  SteadyTime no_eviction_before_{};  // no stream can be evicted before then (spares a scan per refused message)
  int64_t resyncs_ = 0, expired_ = 0, evicted_ = 0, expired_untold_ = 0;
  std::vector<std::string> expired_names_;
  std::string last_resync_;
};

}  // namespace sextant::runtime
