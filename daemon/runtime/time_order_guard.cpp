#include "daemon/runtime/time_order_guard.hpp"

namespace sextant::runtime {

std::optional<std::string> TimeOrderGuard::check(const std::string& stream, int64_t utime, bool strictly_increasing) {
  auto it = last_.find(stream);
  if (it != last_.end()) {
    if (utime == it->second)
      return "duplicate utime " + std::to_string(utime) + " for " + stream;
    if (strictly_increasing && utime < it->second)
      return "utime " + std::to_string(utime) + " before the previous " + std::to_string(it->second) + " for " + stream;
  }
  if (it == last_.end() || utime > it->second) last_[stream] = utime;
  return std::nullopt;
}

}  // namespace sextant::runtime
