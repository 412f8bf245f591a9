#pragma once
// Republishes an LCM log to a live bus at the pace of the messages' own utimes (like lcm-logplayer, which paces by
// the log's receive stamps), in their order (TimeOrderedLog).  Records that carry no sextant utime keep their log
// stamp.
#include "daemon/runtime/lcm_log.hpp"

#include <cstdint>
#include <string>

namespace sextant::tools {

struct RealtimeOptions {
  double speed = 1.0;  // 2 = twice as fast
  /// A longer stretch of log time between two messages plays as this long (divided by speed): a message whose
  /// sender's clock said 1970 must not hold the rest of the log back for 56 years.
  double max_gap_s = 10.0;
  std::string lcm_url;  // empty: LCM's default
};

struct RealtimePlayback {
  int64_t published = 0;
  int64_t gaps_shortened = 0;  // stretches longer than max_gap_s
  double log_seconds_skipped = 0;
  runtime::LogDamage damage;  // what the reader skipped (the caller reports it)
};

/// Plays `log_path` on the bus.  The good events of a damaged log are played.  Throws std::runtime_error when the
/// log cannot be read or the bus cannot be opened.
RealtimePlayback play_realtime(const std::string& log_path, const RealtimeOptions& options);

}  // namespace sextant::tools
