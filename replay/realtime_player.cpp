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

int64_t play_realtime(const std::string& log_path, double speed, const std::string& lcm_url,
                      runtime::LogDamage* damage) {
  TimeOrderedLog log(log_path);
  if (damage != nullptr) *damage = log.damage();
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) throw std::runtime_error(runtime::bus_failure_help(lcm_url));
  const auto wall0 = std::chrono::steady_clock::now();
  std::optional<int64_t> t0;
  int64_t published = 0;
  log.for_each([&](const runtime::LogRecord& r) {
    const int64_t t = peek_utime(r.data).value_or(r.timestamp);
    if (!t0) t0 = t;
    const auto due = wall0 + std::chrono::microseconds(static_cast<int64_t>(static_cast<double>(t - *t0) / speed));
    std::this_thread::sleep_until(due);
    lcm.publish(r.channel, r.data.data(), static_cast<unsigned>(r.data.size()));
    ++published;
  });
  return published;
}

}  // namespace sextant::tools
