#include "daemon/runtime/source_claims.hpp"

#include <algorithm>
#include <cmath>

namespace sextant::runtime {

SourceClaims::SourceClaims(double handover_s, size_t max_streams)
    : handover_us_(static_cast<int64_t>(std::llround(std::max(handover_s, 0.0) * 1e6))),
      max_streams_(std::max<size_t>(max_streams, 1)) {}

bool SourceClaims::claim(const std::string& stream, const std::string& sender, int64_t utime) {
  auto it = holders_.find(stream);
  if (it == holders_.end()) {
    if (holders_.size() >= max_streams_)
      holders_.erase(std::min_element(holders_.begin(), holders_.end(), [](const auto& a, const auto& b) {
        return a.second.last_utime < b.second.last_utime;
      }));
    holders_.emplace(stream, Holder{sender, utime});
    return true;
  }
  Holder& h = it->second;
  if (h.sender == sender) {
    h.last_utime = std::max(h.last_utime, utime);
    return true;
  }
  if (utime - h.last_utime >= handover_us_) {  // the holder went silent: hand over
    h = Holder{sender, utime};
    return true;
  }
  ++refused_;
  return false;
}

}  // namespace sextant::runtime
