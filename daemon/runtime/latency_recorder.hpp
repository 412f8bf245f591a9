#pragma once
// Latency percentiles over a sliding window of the most recent samples (fixed memory).
#include <algorithm>
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
  explicit LatencyRecorder(size_t window = 4096) : ring_(window) {}

  void add(double ms) {
    std::lock_guard lock(mutex_);
    ring_[next_ % ring_.size()] = ms;
    ++next_;
  }

  /// Percentiles by the nearest-rank method over the window.
  LatencySummary summary() const {
    std::vector<double> v;
    {
      std::lock_guard lock(mutex_);
      const size_t n = std::min(next_, ring_.size());
      v.assign(ring_.begin(), ring_.begin() + static_cast<std::ptrdiff_t>(n));
    }
    LatencySummary s;
    s.samples = v.size();
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    auto rank = [&](double p) { return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))]; };
    s.p50_ms = rank(0.50);
    s.p90_ms = rank(0.90);
    s.p99_ms = rank(0.99);
    s.max_ms = v.back();
    return s;
  }

  /// The raw window (oldest first is not guaranteed), for histograms in reports.
  std::vector<double> samples() const {
    std::lock_guard lock(mutex_);
    const size_t n = std::min(next_, ring_.size());
    return {ring_.begin(), ring_.begin() + static_cast<std::ptrdiff_t>(n)};
  }

 private:
  mutable std::mutex mutex_;
  std::vector<double> ring_;
  size_t next_ = 0;
};

}  // namespace sextant::runtime
