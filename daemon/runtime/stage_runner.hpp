#pragma once
// Runs one engine stage on its own thread, fed by a bounded queue.  The producer never blocks: a full queue drops
// the event and counts it.  Latency is measured from the moment the event was received to the end of `handle`.
// Nothing leaves the thread: an exception from the stage (a CHOLMOD failure in the smoother, an allocation) is
// caught, counted ("stage_failures", the message kept as `last_failure` and logged), and the stage is asked to
// recover (Stage::recover: reset the body, rebuild a factorization) before the next event.
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/bounded_queue.hpp"
#include "daemon/runtime/latency_recorder.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>

namespace sextant::runtime {

struct QueuedEvent {
  engine::Event event;
  std::chrono::steady_clock::time_point received;
};

struct StageStatus {
  std::string name;
  size_t queue_depth = 0, queue_capacity = 0;
  int64_t processed = 0, dropped = 0;
  LatencySummary latency;
  engine::Counters counters;  // the stage's own, then "stage_failures" and "stage_recoveries"
  std::string last_failure;   // what the last exception said ("" when none)
};

class StageRunner {
 public:
  /// Status latencies cover the last 4096 events of at most this many seconds.
  static constexpr double kLatencyWindowS = 10.0;

  /// `emit` must be thread-safe (the publisher is).
  StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit);
  ~StageRunner();
  StageRunner(const StageRunner&) = delete;
  StageRunner& operator=(const StageRunner&) = delete;

  /// Offers an event if the stage accepts it; false when the stage accepted it but the queue was full (dropped).
  bool offer(const QueuedEvent& event);
  bool accepts(const engine::Event& event) const { return stage_.accepts(event); }
  /// Has the stage forget a body (Stage::forget) on its own thread, before it handles its next event (any thread).
  void forget(const std::string& source) {
    std::lock_guard lock(forget_mutex_);
    if (forget_.size() < 4096) forget_.push_back(source);
  }

  void start();
  /// Refuses further events (what is queued stays).
  void stop_intake() { queue_.close(); }
  /// Stops intake, processes what is queued, calls the stage's `finish`, joins the thread.
  void drain_and_stop();
  /// The same, bounded: what is still queued at `deadline` is discarded (counted in `drain_discarded`, returned).
  /// The event being handled and the stage's `finish` still run to their end.
  int64_t drain_and_stop(std::chrono::steady_clock::time_point deadline);

  StageStatus status() const;
  /// Runs `f(stage)` between two events (the stage's thread waits meanwhile): how the state directory saves a
  /// running stage (Stage::save).  Also safe before start and after drain_and_stop.
  template <class F>
  void with_stage(F&& f) {
    std::lock_guard lock(stage_mutex_);
    f(stage_);
  }
  const LatencyRecorder& latency() const { return latency_; }

 private:
  void loop();
  // A call into the stage threw: counted, logged (the first ten, then every power of two), kept as the last failure.
  void count_failure(const std::string& message);

  engine::Stage& stage_;
  std::mutex stage_mutex_;  // held while the stage works on an event (and by with_stage)
  engine::Emit emit_;
  BoundedQueue<QueuedEvent> queue_;
  LatencyRecorder latency_;
  std::thread thread_;
  std::atomic<int64_t> processed_{0};
  std::atomic<int64_t> failures_{0}, recoveries_{0}, drain_discarded_{0};
  mutable std::mutex counters_mutex_;
  engine::Counters counters_;  // copied from the stage after each event (the stage is not thread-safe)
  std::string last_failure_;   // under counters_mutex_
  std::mutex forget_mutex_;
  std::vector<std::string> forget_;  // bodies to forget before the next event (under forget_mutex_)
};

}  // namespace sextant::runtime
