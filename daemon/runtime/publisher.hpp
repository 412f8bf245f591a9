#pragma once
// The single way out of sextant: engine outputs -> LCM messages on their channels, stamped with the sender name
// and a per-channel sequence number.  Used by sextantd (raw sink = the LCM bus) and by replay (raw sink = a log
// or memory), so both publish exactly the same bytes.
//
// Routing: FusedPose of the primary estimator -> FUSED_POSE; of any other estimator -> FUSED_POSE_<ESTIMATOR>
// (e.g. FUSED_POSE_DEAD_RECKONING), so estimators can be compared live.  A FusedPose whose utime is not after
// the last one published for its source on that channel is dropped and counted ("fused_pose_not_monotonic").
// That last time is kept per channel and source for at most `max_tracked` of them (a new one beyond evicts the one
// published longest ago in data time, counted); a body the stages forget (idle, or its clock re-synchronised) is
// forgotten here too (`forget`), so that its new clock is not refused.
// Lag (sextantd): given a wall clock (`measure_lag`), each FusedPose published is compared with it; how far behind
// real time the daemon publishes (wall clock minus the pose's utime: the sender's latency, the queues, a stall) is
// in the pose itself (fused_pose_t.lag_us) and on the status channel (publish_lag_us, publish_lag_us_max since the
// previous status), so a backlog published after a stall says that it is late.  The lag includes the offset between
// the sender's clock and the daemon's (years, for a log played live with its original stamps), so what signals a
// stall is the lag beyond the usual one: the smallest of the last kUsualLagReports reports (publish_lag_usual_us),
// and the daemon warns when the lag grows (Lag::falling_behind), not when it falls back towards the usual.
// Without a wall clock (replay) the poses' lag_us is 0.
// Thread-safe.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/outputs.hpp"

#include <sextant/status_t.hpp>

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace sextant::runtime {

class Publisher {
 public:
  /// `raw(channel, bytes, utime)` delivers one encoded message.
  using RawSink = std::function<void(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime)>;

  static constexpr size_t kDefaultMaxTracked = 4096;

  Publisher(config::Channels channels, std::string sender, std::string primary_estimator, RawSink raw,
            size_t max_tracked = kDefaultMaxTracked);

  /// Publishes one engine output; false when it was not published (a FusedPose not after the last one).
  bool publish(const engine::Output& output);
  void publish(const sextant::status_t& status);

  /// Messages published per channel.
  std::map<std::string, int64_t> counts() const;
  /// Bytes published per channel (LCM payloads).
  std::map<std::string, int64_t> bytes() const;
  int64_t not_monotonic() const;
  /// Forgets the last FusedPose time of `source` from `estimator` (after the stage forgot the body).
  void forget(const std::string& estimator, const std::string& source);
  /// Channel and source pairs whose last FusedPose time is kept now; forgotten ones; evicted at the bound.
  size_t fused_pose_sources() const;
  int64_t fused_pose_sources_forgotten() const;
  int64_t fused_pose_sources_evicted() const;
  const std::string& sender() const { return sender_; }
  /// Measures each FusedPose's lag against `wall_utime()` (microseconds since the epoch) from now on.
  void measure_lag(std::function<int64_t()> wall_utime);
  struct Lag {
    int64_t last_us = 0;      // of the last FusedPose published
    int64_t max_us = 0;       // the largest since the previous take_lag
    int64_t usual_us = 0;     // the smallest over the last kUsualLagReports calls that saw a pose (0: none yet)
    int64_t previous_us = 0;  // last_us at the previous call that saw a pose (max_us at the first)
    /// How far the largest exceeds the usual (a stall, or a backlog), microseconds.
    int64_t excess_us() const { return max_us - usual_us; }
    /// Whether the daemon fell behind since the previous call: the lag jumped by more than `threshold_us` over its
    /// previous value (a stall, now published as a backlog), or it stands more than `threshold_us` over the usual
    /// and still grows (by over a tenth of the threshold: input faster than the daemon).  A lag that falls is not
    /// (a log played faster than real time, a backlog draining), however far it is from the usual.
    bool falling_behind(int64_t threshold_us) const {
      return max_us - previous_us > threshold_us ||
             (excess_us() > threshold_us && last_us - previous_us > threshold_us / 10);
    }
  };
  /// Reports (take_lag calls, one per status period) over which the usual lag is the smallest seen: long enough
  /// that a stall does not become the usual, short enough to follow a sender whose clock was set.
  static constexpr size_t kUsualLagReports = 120;
  /// The lag since the previous call (its maximum and minimum restart).
  Lag take_lag();
  /// The channel a FusedPose of `estimator` is published on.
  std::string fused_pose_channel(const std::string& estimator) const;

 private:
  template <class Msg>
  void send(const std::string& channel, Msg msg);

  const config::Channels channels_;
  const std::string sender_;
  const std::string primary_;
  RawSink raw_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> seq_;
  std::map<std::string, int64_t> bytes_;
  const size_t max_tracked_;
  std::map<std::string, int64_t> last_fused_utime_;  // by channel + "/" + source, at most max_tracked_
  int64_t not_monotonic_ = 0, forgotten_ = 0, evicted_ = 0;
  std::function<int64_t()> wall_;
  Lag lag_;
  std::optional<int64_t> lag_min_;       // the smallest since the previous take_lag
  std::deque<int64_t> lag_minima_;       // of the last kUsualLagReports take_lag calls that saw a pose
  std::optional<int64_t> lag_reported_;  // last_us at the last take_lag call that saw a pose
};

}  // namespace sextant::runtime
