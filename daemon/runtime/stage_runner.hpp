#pragma once
// Runs one engine stage on its own thread, fed by a bounded queue.  The producer never blocks: a full queue drops
// the event and counts it.  Latency is measured from the moment the event was received to the end of `handle`.
// With odometry batching (the graph stage's, odometry_batcher.hpp) a body's odometry waits in batches behind one
// queue slot each; the thread hands every message of a batch to `handle` on its own, as replay does.
// Each event is handled through the stage's StageHost (stage_host.hpp), as replay handles it: nothing leaves the
// thread (an exception from the stage is caught, counted as "stage_failures", kept as `last_failure` and logged, and
// the stage recovers before the next event), and a forgotten body is forgotten by the publisher after the stage's
// earlier outputs.
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/bounded_queue.hpp"
#include "daemon/runtime/latency_recorder.hpp"
#include "daemon/runtime/odometry_batcher.hpp"
#include "daemon/runtime/queued_event.hpp"
#include "daemon/runtime/stage_host.hpp"

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <unordered_set>
#include <variant>

namespace sextant::runtime {

struct StageStatus {
  std::string name;
  size_t queue_depth = 0, queue_capacity = 0;  // queue slots (a batch of odometry takes one)
  int64_t processed = 0, dropped = 0;          // events (a batch counts its messages)
  LatencySummary latency;
  /// The stage's own, then "stage_failures" and "stage_recoveries"; with odometry batching also
  /// "odometry_coalesced" (messages that joined a waiting batch), "odometry_waiting" (messages in batches now) and
  /// "odometry_waiting_dropped" (dropped at a bound of the batcher, also in `dropped`); "resync_forgets": bodies
  /// forgotten because their clock was re-synchronised.
  engine::Counters counters;
  std::string last_failure;  // what the last exception said ("" when none)
};

class StageRunner {
 public:
  /// Status latencies cover the last 4096 events of at most this many seconds.
  static constexpr double kLatencyWindowS = 10.0;

  /// `emit` must be thread-safe (the publisher is).  `batching`: the stage's odometry goes through an OdometryBatcher.
  StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit,
              std::optional<OdometryBatcherOptions> batching = std::nullopt);
  ~StageRunner();
  StageRunner(const StageRunner&) = delete;
  StageRunner& operator=(const StageRunner&) = delete;

  /// Offers an event the stage accepts (one thread at a time: the intake's); false when it was dropped (the queue was
  /// full, or a bound of the batcher was reached).
  bool offer(const QueuedEvent& event);
  bool accepts(const engine::Event& event) const { return host_.stage().accepts(event); }
  /// Has the stage forget a body (Stage::forget) on its own thread, in order with the events offered before (one
  /// thread at a time: the intake's): the order takes a queue slot (and closes the body's odometry batch), so the
  /// body's earlier events are handled first.  When the queue is full the order is kept aside and carried out before
  /// the stage's next event, counted as "forget_out_of_order" (the bodies the intake forgets are at most
  /// daemon.max_sources at a time, so the orders kept aside are bounded too).
  void forget(const std::string& source);
  /// Called on the stage's thread each time the stage forgot a body (after idling, or before the first message of a
  /// re-synchronised clock, QueuedEvent::forget_first), after the stage's earlier outputs: how the publisher forgets
  /// what it keeps for that body.  Set before start.
  void on_forget(StageHost::ForgetHook hook) { host_.on_forget(std::move(hook)); }

  void start();
  /// Refuses further events (what is queued stays).
  void stop_intake() { queue_.close(); }
  /// Stops intake, processes what is queued, calls the stage's `finish`, joins the thread.
  void drain_and_stop();
  /// The same, bounded: what is still queued at `deadline` is discarded (counted in `drain_discarded`, returned),
  /// and a stage still at work then is interrupted (Stage::interrupt, counted in `drain_interrupted` and logged): the
  /// event being handled ends after the step under way (a graph solve after its Gauss-Newton iteration), then the
  /// stage's `finish` runs.  So the drain takes `deadline` plus one such step.
  int64_t drain_and_stop(std::chrono::steady_clock::time_point deadline);

  StageStatus status() const;
  /// Runs `f(stage)` between two events (the stage's thread waits meanwhile): how the state directory saves a
  /// running stage (Stage::save).  Also safe before start and after drain_and_stop.
  template <class F>
  void with_stage(F&& f) {
    std::lock_guard lock(stage_mutex_);
    f(host_.stage());
  }
  const LatencyRecorder& latency() const { return latency_; }

 private:
  void loop();
  // Hands one event to the stage (the stage's lock held) and records its latency.
  void handle_one(const QueuedEvent& event);
  // Copies the stage's counters out for status() (the stage's lock held).
  void copy_counters();

  StageHost host_;
  std::mutex stage_mutex_;  // held while the stage works on an event (and by with_stage)
  // The order to forget a body, in the queue.
  struct ForgetOrder {
    std::string body;
  };
  // A queue slot: one event, the token of a batch of one body's odometry, or an order to forget a body.
  using Slot = std::variant<QueuedEvent, OdometryBatcher::Token, ForgetOrder>;
  BoundedQueue<Slot> queue_;
  std::unique_ptr<OdometryBatcher> batcher_;  // null without batching
  LatencyRecorder latency_;
  std::thread thread_;
  std::atomic<int64_t> processed_{0};
  std::atomic<int64_t> drain_discarded_{0};
  std::atomic<int64_t> drain_interrupted_{0};
  std::atomic<bool> finished_{false};  // the thread has run the stage's finish
  mutable std::mutex counters_mutex_;
  engine::Counters counters_;  // copied from the stage after each event (the stage is not thread-safe)
  std::mutex forget_mutex_;
  std::unordered_set<std::string> forget_;  // orders the full queue refused, carried out before the next event
  std::atomic<int64_t> forget_out_of_order_{0};
};

}  // namespace sextant::runtime
