#include "replay/realtime_player.hpp"

#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/time_ordered_log.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <optional>
#include <stdexcept>
#include <thread>

namespace sextant::tools {

RealtimePlayback play_realtime(const std::string& log_path, const RealtimeOptions& options) {
  TimeOrderedLog log(log_path);
  RealtimePlayback out;
  out.damage = log.damage();
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error(runtime::bus_failure_help(options.lcm_url));
  const auto wall0 = std::chrono::steady_clock::now();
  const double max_gap_us = options.max_gap_s * 1e6;
  std::optional<int64_t> previous;
  double played_us = 0;  // log time played so far, long gaps shortened
  log.for_each([&](const runtime::LogRecord& r) {
    const int64_t t = replay_stamp(r);
    if (previous) {
      // The difference as a double: stamps at int64's ends must not overflow it.
      const double gap = static_cast<double>(t) - static_cast<double>(*previous);
      if (gap > max_gap_us) {
        ++out.gaps_shortened;
        out.log_seconds_skipped += (gap - max_gap_us) * 1e-6;
      }
      played_us += std::min(gap, max_gap_us);
    }
    previous = t;
    std::this_thread::sleep_until(wall0 + std::chrono::microseconds(static_cast<int64_t>(played_us / options.speed)));
    lcm.publish(r.channel, r.data.data(), static_cast<unsigned>(r.data.size()));
    ++out.published;
  });
  return out;
}

}  // namespace sextant::tools
