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
  /// `output_bytes`: bytes per output channel since start; the report also gives the rate since the previous build.
  sextant::status_t build(double uptime_s, const std::map<std::string, ChannelCounts>& channels,
                          const std::vector<StageStatus>& stages, const engine::Counters& runtime_counters,
                          const std::map<std::string, int64_t>& output_counts,
                          const std::map<std::string, int64_t>& output_bytes = {});

 private:
  std::string sender_;
  double previous_uptime_s_ = 0;
  std::map<std::string, int64_t> previous_bytes_;
};

}  // namespace sextant::runtime
