#pragma once
// Replay's lanes on two threads, with the outputs of the one-thread lanes in the same order (StageLanes::kPipelined,
// engine_driver.hpp).  The stages are split in two groups: the caller's thread runs one, a worker thread the other;
// every event goes to both groups in input order, each group's stages in stage order.  What a stage does with an
// event (its outputs, the bodies it forgot, its processing time) is captured, not published; once both groups have
// handled an event, its captures are handed to `deliver` on the caller's thread, ordered as the one-thread lanes
// would have produced them: first what happened before the event (forgetting expired bodies), then stage by stage.
// The groups never share state: the graph stage and the graph pose stage (which reads the corrections the graph
// posts) are on the same side, so each stage sees the same inputs in the same order as on one thread, and the
// published bytes are the same.
//
// Bounded: at most `capacity` events are in flight (routed, not yet delivered); route() waits for the worker when
// they are, until half of them are delivered.  Nothing is dropped: this is a replay's lane, not a live daemon's.
// An event in flight holds its captures, a few KB: 4,096 of them added 20-30 MB to the 8-robot fleet replay's
// resident memory; 512 keep the worker fed (the caller's side is a fifth of the work).
#include "daemon/engine/outputs.hpp"
#include "daemon/runtime/queued_event.hpp"
#include "daemon/runtime/stage_host.hpp"

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

namespace sextant::runtime {

/// One thing a stage did, as the one-thread lanes would have done it at once.
struct StageCapture {
  struct Forgot {
    std::string body;
  };
  struct Handled {
    double ms = 0;  // the stage's processing time of the event
  };
  int phase = 1;     // 0: before the event (expired bodies forgotten), 1: the event
  size_t stage = 0;  // index in stage order
  std::variant<engine::Output, Forgot, Handled> what;
};

class PipelinedLanes {
 public:
  using Deliver = std::function<void(StageCapture&)>;

  /// `on_worker[i]`: stage i runs on the worker thread.  `deliver` is called on the caller's thread.
  PipelinedLanes(std::vector<char> on_worker, Deliver deliver, size_t capacity = 512);
  /// The stages' hosts in stage order, each made with emit_into(i) and on_forget(forgot_into(i)); starts the worker.
  void attach(std::vector<StageHost*> hosts);
  ~PipelinedLanes();
  PipelinedLanes(const PipelinedLanes&) = delete;
  PipelinedLanes& operator=(const PipelinedLanes&) = delete;

  /// The emit and forget hook of host `stage`: they append to the event its thread is handling.
  engine::Emit emit_into(size_t stage);
  StageHost::ForgetHook forgot_into(size_t stage);

  /// Every stage forgets `body` before the next event (the bodies the intake expired).
  void forget_before_next(const std::string& body) { forget_next_.push_back(body); }
  /// Hands `event` to every stage that accepts it, and delivers every event both groups are done with.
  void route(QueuedEvent event);
  /// Waits until every routed event has been delivered (the worker is then idle until the next route()).
  void settle();
  /// settle(), the worker's end, then every stage's finish() in stage order on this thread, delivered.
  void finish();

 private:
  struct InFlight {
    QueuedEvent event;
    std::vector<std::string> forget;
    std::vector<StageCapture> caller, worker;  // each group's captures, in (phase, stage) order
    std::atomic<bool> done{false};             // the worker's group has handled it
  };

  // Runs group `worker` (true: the worker's) of one event, capturing into its list.
  void run_group(InFlight& item, bool worker);
  void worker_loop();
  // The worker handles what it was handed, then ends (finish() and the destructor).
  void stop_worker();
  // Hands the pending batch to the worker.
  void hand_over();
  // Waits until the worker's group has handled `item` (and so every event before it).
  void wait_for(InFlight& item);
  // Delivers the events at the front that both groups are done with.
  void deliver_done();
  void deliver(InFlight& item);

  std::vector<StageHost*> hosts_;
  std::vector<char> on_worker_;
  Deliver deliver_;
  const size_t capacity_;
  std::vector<std::string> forget_next_;
  std::deque<std::unique_ptr<InFlight>> in_flight_;            // routed, not delivered (caller's thread only)
  std::vector<InFlight*> batch_;                               // routed, not yet handed to the worker
  std::vector<StageCapture>* target_[2] = {nullptr, nullptr};  // where each thread's hosts capture now
  bool forgetting_expired_[2] = {false, false};                // each thread: forgetting before its event

  std::mutex mutex_;
  std::condition_variable to_worker_, to_caller_;
  std::deque<InFlight*> queue_;              // handed to the worker, not yet taken (under mutex_)
  bool stop_ = false;                        // under mutex_
  std::atomic<InFlight*> awaited_{nullptr};  // the event the caller waits for (worker: notify when done)
  std::thread worker_;
};

}  // namespace sextant::runtime
