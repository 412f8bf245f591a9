#include "daemon/runtime/status_report.hpp"

#include "daemon/runtime/version.hpp"

namespace sextant::runtime {
namespace {

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void put_counters(sextant::stage_status_t& s, const engine::Counters& counters) {
  s.num_counters = static_cast<int32_t>(counters.size());
  for (const auto& [name, value] : counters) {
    s.counter_names.push_back(name);
    s.counter_values.push_back(value);
  }
}

}  // namespace

sextant::status_t StatusReport::build(double uptime_s, const std::map<std::string, ChannelCounts>& channels,
                                      const std::vector<StageStatus>& stages, const engine::Counters& runtime_counters,
                                      const std::map<std::string, int64_t>& output_counts,
                                      const std::map<std::string, int64_t>& output_bytes) {
  sextant::status_t m{};
  m.utime = wall_utime();
  m.sender = sender_;
  m.version = sextant::version();
  m.uptime_s = uptime_s;
  for (const auto& [name, c] : channels) {
    sextant::channel_status_t x{};
    x.channel = name;
    x.received = c.received;
    x.decoded = c.decoded;
    x.rejected = c.rejected;
    x.dropped = c.dropped;
    x.lost = c.lost;
    x.num_reasons = static_cast<int32_t>(c.reasons.size());
    for (const auto& [reason, count] : c.reasons) {
      x.reasons.push_back(reason);
      x.reason_counts.push_back(count);
    }
    x.last_error = c.last_error;
    for (const auto& [sender, n] : c.lost_by_sender) {
      x.lost_senders.push_back(sender);
      x.lost_counts.push_back(n);
    }
    x.num_lost_senders = static_cast<int32_t>(x.lost_senders.size());
    m.channels.push_back(x);
  }
  m.num_channels = static_cast<int32_t>(m.channels.size());
  for (const auto& s : stages) {
    sextant::stage_status_t x{};
    x.name = s.name;
    x.queue_depth = static_cast<int32_t>(s.queue_depth);
    x.queue_capacity = static_cast<int32_t>(s.queue_capacity);
    x.processed = s.processed;
    x.dropped = s.dropped;
    x.latency_ms_p50 = s.latency.p50_ms;
    x.latency_ms_p90 = s.latency.p90_ms;
    x.latency_ms_p99 = s.latency.p99_ms;
    x.latency_ms_max = s.latency.max_ms;
    put_counters(x, s.counters);
    x.last_failure = s.last_failure;
    m.stages.push_back(x);
  }
  sextant::stage_status_t runtime{};
  runtime.name = "runtime";
  put_counters(runtime, runtime_counters);
  m.stages.push_back(runtime);
  m.num_stages = static_cast<int32_t>(m.stages.size());
  m.num_outputs = static_cast<int32_t>(output_counts.size());
  const double period = uptime_s - previous_uptime_s_;
  for (const auto& [channel, count] : output_counts) {
    m.output_channels.push_back(channel);
    m.output_counts.push_back(count);
    const auto b = output_bytes.find(channel);
    const int64_t total = b == output_bytes.end() ? 0 : b->second;
    m.output_bytes.push_back(total);
    const auto before = previous_bytes_.find(channel);
    const int64_t delta = total - (before == previous_bytes_.end() ? 0 : before->second);
    m.output_bytes_per_s.push_back(period > 0 ? static_cast<double>(delta) / period : 0.0);
  }
  previous_uptime_s_ = uptime_s;
  previous_bytes_ = output_bytes;
  return m;
}

}  // namespace sextant::runtime
