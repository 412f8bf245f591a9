#pragma once
// Runs one engine stage on its own thread, fed by a bounded queue.  The producer never blocks: a full queue drops
// the event and counts it.  Latency is measured from the moment the event was received to the end of `handle`.
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
  engine::Counters counters;
};

class StageRunner {
 public:
  /// `emit` must be thread-safe (the publisher is).
  StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit);
  ~StageRunner();
  StageRunner(const StageRunner&) = delete;
  StageRunner& operator=(const StageRunner&) = delete;

  /// Offers an event if the stage accepts it; false when the stage accepted it but the queue was full (dropped).
  bool offer(const QueuedEvent& event);
  bool accepts(const engine::Event& event) const { return stage_.accepts(event); }

  void start();
  /// Stops intake, processes what is queued, calls the stage's `finish`, joins the thread.
  void drain_and_stop();

  StageStatus status() const;
  const LatencyRecorder& latency() const { return latency_; }

 private:
  void loop();

  engine::Stage& stage_;
  engine::Emit emit_;
  BoundedQueue<QueuedEvent> queue_;
  LatencyRecorder latency_;
  std::thread thread_;
  std::atomic<int64_t> processed_{0};
  mutable std::mutex counters_mutex_;
  engine::Counters counters_;  // copied from the stage after each event (the stage is not thread-safe)
};

}  // namespace sextant::runtime
