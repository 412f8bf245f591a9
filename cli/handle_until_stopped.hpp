#pragma once
// The receive loop of the live tools (listen, watch): handle LCM messages until SIGINT/SIGTERM, until `seconds`
// have passed (when > 0), or until `done()` says so.
#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <functional>

namespace sextant::cli {

inline std::atomic<bool>& stop_requested() {
  static std::atomic<bool> flag{false};
  return flag;
}

inline void handle_until_stopped(lcm::LCM& lcm, double seconds, const std::function<bool()>& done = {}) {
  std::signal(SIGINT, [](int) { stop_requested() = true; });
  std::signal(SIGTERM, [](int) { stop_requested() = true; });
  const auto start = std::chrono::steady_clock::now();
  while (!stop_requested() && !(done && done())) {
    lcm.handleTimeout(100);
    if (seconds > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > seconds) break;
  }
}

}  // namespace sextant::cli
