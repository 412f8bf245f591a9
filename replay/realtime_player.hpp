#pragma once
// Republishes an LCM log to a live bus at the pace of the messages' own utimes (like lcm-logplayer, which paces by
// the log's receive stamps).  Records that carry no sextant utime keep their log stamp.
#include "daemon/runtime/lcm_log.hpp"

#include <cstdint>
#include <string>

namespace sextant::tools {

/// Plays `log_path` at `speed` (2 = twice as fast) on `lcm_url`; returns the number of messages published.  The
/// good events of a damaged log are played; what was skipped goes into `damage` when given (the caller reports it).
/// Throws std::runtime_error when the log cannot be read or the bus cannot be opened.
int64_t play_realtime(const std::string& log_path, double speed, const std::string& lcm_url,
                      runtime::LogDamage* damage = nullptr);

}  // namespace sextant::tools
