#pragma once
// Builds the status_t message published on SEXTANT_STATUS.
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <sextant/status_t.hpp>

#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace sextant::runtime {

class StatusReport {
 public:
  explicit StatusReport(std::string sender) : sender_(std::move(sender)) {}

  /// `runtime_counters` go into an extra stage entry named "runtime" (publisher and recorder counters).
  sextant::status_t build(double uptime_s, const std::map<std::string, ChannelCounts>& channels,
                          const std::vector<StageStatus>& stages, const engine::Counters& runtime_counters,
                          const std::map<std::string, int64_t>& output_counts) const;

 private:
  std::string sender_;
};

}  // namespace sextant::runtime
