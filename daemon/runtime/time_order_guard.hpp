#pragma once
// Rejects duplicate and backwards timestamps per stream (a channel and a source or sensor).  Odometry must be
// strictly increasing per source; other inputs only refuse exact duplicates (the stages accept late data).
#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace sextant::runtime {

class TimeOrderGuard {
 public:
  /// nullopt when `utime` is acceptable for `stream` (and records it), else the reason text.
  std::optional<std::string> check(const std::string& stream, int64_t utime, bool strictly_increasing);

 private:
  std::map<std::string, int64_t> last_;
};

}  // namespace sextant::runtime
