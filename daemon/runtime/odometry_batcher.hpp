#pragma once
// Per-body odometry batches in front of a stage's bounded queue: the daemon's intake thread -> the graph stage's thread.
//
// A body publishing odometry at 1 kHz would fill the graph stage's queue during a long solve, and the queue would then
// drop whatever comes next: other bodies' odometry, loops, sightings.  So the graph stage's runner hands each odometry
// message to this batcher instead of taking one queue slot per message:
//  - a body's odometry arriving while an earlier batch of that body still waits in the queue joins that batch: the
//    queue holds one token per batch, and when the stage's thread pops the token it takes the whole batch and hands
//    its messages to the stage one by one, in arrival order, exactly as replay hands it single messages.  Nothing is
//    merged and no keyframe is decided here: the stage's own KeyframeSelector decides every pose, so the live daemon
//    takes the replay's decisions by construction;
//  - any other event of the body (a loop, a sighting) that the queue takes closes the body's batch: the next odometry
//    starts a new batch behind it, so each body's events reach the stage in arrival order (events of different bodies
//    may overtake each other; the graph keeps each body's state apart).  An event the queue refuses closes nothing;
//  - a batch holds at most `max_batch` messages; the next message starts a new batch (one more token);
//  - a token the queue refuses drops its batch (the message that opened it), counted by the queue as a drop;
//  - memory: at most `max_waiting_per_body` messages of one body and `max_waiting` of all bodies wait in batches (a
//    QueuedEvent is 1120 bytes, one allocation each: a batch is a deque, whose blocks hold one such element, so the
//    memory follows the count without a vector's doubling); a message beyond either bound is dropped and counted
//    (`dropped`).
// Thread safety: `offer` on the intake thread, `take` on the stage's thread, the counts anywhere.  One mutex, held for
// the bookkeeping and while `offer` calls the queue (so an offer is one step for `take`); the queue's lock nests inside
// it, and `take` is called after the pop has released the queue's lock, so the two never wait for each other in a cycle.
#include "daemon/runtime/queued_event.hpp"

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace sextant::runtime {

struct OdometryBatcherOptions {
  size_t max_batch = 256;               // messages per batch (per queue token)
  size_t max_waiting_per_body = 16384;  // messages of one body waiting in batches (16 s of a 1 kHz body, 18 MB)
  size_t max_waiting = 65536;           // messages of all bodies waiting in batches (71 MB)
};

class OdometryBatcher {
 public:
  /// The messages of one body behind one queue token (what the queue holds is a Token).
  class Batch;
  using Token = std::shared_ptr<Batch>;
  using EnqueueEvent = std::function<bool(const QueuedEvent&)>;
  using EnqueueToken = std::function<bool(const Token&)>;

  /// Throws std::invalid_argument for a bound of 0.
  explicit OdometryBatcher(const OdometryBatcherOptions& options);

  /// Intake thread: an event for the stage.  Odometry joins its body's waiting batch, or opens a new one whose token
  /// `enqueue_token` queues; any other event goes to `enqueue_event` and, once queued, closes its body's batch.
  /// False: the event was dropped (the queue refused it or its token, or a bound was reached).
  bool offer(const QueuedEvent& event, const EnqueueEvent& enqueue_event, const EnqueueToken& enqueue_token);

  /// Intake thread: queues `marker` (through `enqueue`) as an event of `body` that is not odometry: once queued it
  /// closes the body's batch, so the body's later odometry goes into a new batch behind it.  False when the queue
  /// refused it.
  template <class Enqueue>
  bool offer_marker(const std::string& body, const Enqueue& enqueue) {
    std::lock_guard lock(mutex_);
    if (!enqueue()) return false;
    if (auto it = bodies_.find(body); it != bodies_.end()) it->second.open.reset();
    return true;
  }

  /// Stage thread: the messages of a popped token's batch, in arrival order.  The batch is closed: the body's next
  /// message opens a new one.
  std::deque<QueuedEvent> take(const Token& token);

  int64_t coalesced() const;  // messages that joined a waiting batch (no queue slot of their own)
  int64_t waiting() const;    // messages waiting in batches now
  int64_t dropped() const;    // messages dropped at a bound (max_waiting_per_body, max_waiting)

 private:
  struct Body {
    Token open;          // the batch still waiting in the queue that the next message joins (null: none)
    size_t waiting = 0;  // messages of this body in batches
  };
  OdometryBatcherOptions options_;
  mutable std::mutex mutex_;
  std::map<std::string, Body> bodies_;  // bodies with messages waiting
  size_t waiting_ = 0;
  int64_t coalesced_ = 0, dropped_ = 0;
};

}  // namespace sextant::runtime
