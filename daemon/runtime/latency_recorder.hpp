#pragma once
// Latency percentiles over the recent past: the most recent `capacity` samples (fixed memory) that are also at most
// `window_s` old.  The time window keeps a status report from quoting a flood's latencies long after the queue
// emptied (a window of the last 4096 events alone showed a 5.9 s p50 for 30 s after the graph caught up).
#include "daemon/runtime/nearest_rank_percentile.hpp"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <vector>

namespace sextant::runtime {

struct LatencySummary {
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, max_ms = 0;
  size_t samples = 0;
};

class LatencyRecorder {
 public:
  using Clock = std::chrono::steady_clock;

  /// `window_s` 0: no age limit (the last `capacity` samples).
  explicit LatencyRecorder(size_t capacity = 4096, double window_s = 0)
      : ring_(capacity == 0 ? 1 : capacity),
        window_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(window_s))) {}

  void add(double ms, Clock::time_point now = Clock::now()) {
    std::lock_guard lock(mutex_);
    ring_[next_ % ring_.size()] = {now, ms};
    ++next_;
  }

  /// Percentiles by the nearest-rank method over the window as of `now`.
  LatencySummary summary(Clock::time_point now = Clock::now()) const {
    std::vector<double> v = recent(now);
    LatencySummary s;
    s.samples = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    s.p50_ms = nearest_rank_percentile(v, 0.50);
    s.p90_ms = nearest_rank_percentile(v, 0.90);
    s.p99_ms = nearest_rank_percentile(v, 0.99);
    s.max_ms = v.back();
    return s;
  }

  /// The samples of the window (oldest first is not guaranteed), for histograms in reports.
  std::vector<double> samples(Clock::time_point now = Clock::now()) const { return recent(now); }

 private:
  struct Sample {
    Clock::time_point at;
    double ms = 0;
  };
  std::vector<double> recent(Clock::time_point now) const {
    std::lock_guard lock(mutex_);
    const size_t n = std::min(next_, ring_.size());
    std::vector<double> v;
    v.reserve(n);
    for (size_t i = 0; i < n; ++i)
      if (window_.count() == 0 || now - ring_[i].at <= window_) v.push_back(ring_[i].ms);
    return v;
  }

  mutable std::mutex mutex_;
  std::vector<Sample> ring_;
  Clock::duration window_;
  size_t next_ = 0;
};

}  // namespace sextant::runtime
