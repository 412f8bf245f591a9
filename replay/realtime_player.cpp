#include "replay/realtime_player.hpp"

#include "daemon/runtime/daemon.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <numeric>
#include <stdexcept>
#include <thread>

namespace sextant::tools {

int64_t play_realtime(const std::string& log_path, double speed, const std::string& lcm_url,
                      runtime::LogDamage* damage) {
  auto records = runtime::LogReader::read_all(log_path, damage);
  std::vector<int64_t> keys(records.size());
  for (size_t i = 0; i < records.size(); ++i) keys[i] = peek_utime(records[i].data).value_or(records[i].timestamp);
  std::vector<size_t> order(records.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return keys[a] < keys[b]; });

  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) throw std::runtime_error(runtime::bus_failure_help(lcm_url));
  if (order.empty()) return 0;
  const auto wall0 = std::chrono::steady_clock::now();
  const int64_t t0 = keys[order.front()];
  int64_t published = 0;
  for (size_t i : order) {
    const auto due = wall0 + std::chrono::microseconds(static_cast<int64_t>(static_cast<double>(keys[i] - t0) / speed));
    std::this_thread::sleep_until(due);
    lcm.publish(records[i].channel, records[i].data.data(), static_cast<unsigned>(records[i].data.size()));
    ++published;
  }
  return published;
}

}  // namespace sextant::tools
