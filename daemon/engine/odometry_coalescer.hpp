#pragma once
// Per-body odometry coalescing in front of the graph stage's bounded queue.
//
// In the daemon every stage has one bounded event queue.  A body publishing odometry at 1 kHz fills the graph
// stage's queue while a long solve runs, and the queue then drops whatever comes next: another body's keyframes,
// its loop closures, its sightings.  The graph needs odometry only to decide keyframes and to tie sightings and loops
// to keyframes, so the daemon's intake thread hands a body's odometry to this coalescer instead of the queue:
//  - a body's odometry arriving while an earlier one still waits in the queue is appended to that one's *batch*
//    (the queued event is only a token: when the stage handles it, it takes the whole batch, `take`);
//  - inside a batch, a message is merged into the message before it unless that one is pinned.  Merging keeps the
//    newer pose and covariance and composes the two increments' covariances (Q = Ad(D2^-1) Q1 Ad(D2^-1)' + Q2,
//    compose_covariance in pose_covariance.hpp), so the stage's accumulated odometry covariance is the one it gets
//    from the single messages; the merged message's time and pose are kept in `passed` for the stage's odometry
//    history (loops and sightings at exact odometry times still resolve);
//  - pinned, never merged into: a keyframe candidate (a mirror of the stage's KeyframeSelector decides on every
//    pose here: keyframes and re-anchorings are pinned; too-close and implausible decisions leave the reference
//    unchanged, but implausible ones advance the selector's run towards re-anchoring, so each entry carries the
//    mirror's selector as it was before its message and the stage continues from that one: it takes the same
//    decisions at the same poses as from the single messages; when the stage drops a keyframe it cannot weight, it
//    sends the mirror back to its last keyframe too, keyframe_dropped), and the
//    first message at or after the time of a sighting or a loop that arrived ahead of the odometry (the stage anchors
//    the sighting by interpolating between the two messages around it, and tries the loop again at that message,
//    exactly as without coalescing);
//  - a body's other events (loops, sightings) close its open batch: the next odometry starts a new batch behind them,
//    so each body's events reach the stage in arrival order; one the queue refuses closes nothing and pins nothing
//    (as if it had never come: the odometry after it still merges into the open batch, which needs no queue slot);
//  - out-of-order and duplicate stamps are counted and dropped here, as the stage would.
// Bounds: a batch holds at most `max_entries` messages (pinned or newest) and `max_passed` passed poses per message
// (the oldest half is forgotten beyond it, as the stage's history does); a full batch is closed and the next message
// starts a new one (one more queue slot).  The queue then holds at most one token per body and batch, so its
// capacity is left to loops, sightings and match answers; a token the full queue refuses is dropped and counted by
// the queue as before.
// Thread safety: `offer` runs on the daemon's intake thread, `take` and the counters on the stage's thread; a mutex
// held only for bookkeeping (never while the stage handles an event).  Replay never calls `offer`: the stage then
// handles every odometry message itself.
#include "daemon/engine/events.hpp"
#include "estimators/keyframe/keyframe_selector.hpp"
#include "estimators/lie/se3.hpp"

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sextant::engine {

struct OdometryCoalescerOptions {
  KeyframeSelectorOptions keyframes;    // the graph stage's (planar is taken from each body's first message)
  double min_increment_variance = 1e-10;  // the graph stage's floor on increment variances (pose_covariance.hpp)
  size_t max_entries = 256;             // messages one batch holds unmerged
  size_t max_passed = 100000;           // merged poses kept per message (the graph's odometry_history)
};

class OdometryCoalescer {
 public:
  /// One odometry message for the stage: as received, or the newest of several merged ones.
  struct Entry {
    Odometry message;  // merged: the newest message, its increment_covariance the composed one (before the floor)
    std::vector<std::pair<int64_t, SE3>> passed;  // times and poses of the messages merged into it, oldest first
    int64_t implausible = 0;  // merged messages the keyframe selector found implausible (the stage counts them)
    bool pinned = false;      // a keyframe candidate or the first message after a waiting sighting's or loop's time
    Matrix6 increment = Matrix6::Zero();  // covariance of the motion since the previous message, floor included
    KeyframeDecision decision = KeyframeDecision::kTooClose;  // of `message`
    KeyframeSelector selector;  // the mirror's selector before deciding `message` (after every earlier message)
  };
  using Batch = std::vector<Entry>;

  explicit OdometryCoalescer(const OdometryCoalescerOptions& options);

  /// Intake thread: an event the graph stage accepted.  Odometry is coalesced (`enqueue` called only to queue a
  /// new batch's token); other events close their body's open batch and are queued.  Returns false when the event
  /// (or the token) was dropped because `enqueue` refused it.
  bool offer(const Event& event, const std::function<bool()>& enqueue);

  /// Stage thread: the oldest batch of `source` (called for each odometry event the stage handles; nullopt when the
  /// event did not come through `offer`, as in replay).
  std::optional<Batch> take(const std::string& source);

  /// Stage thread: the stage could not use the keyframe its selector took at `dropped` (an odometry edge it cannot
  /// weight) and went back to `reference`, the last keyframe in its graph (KeyframeSelector::reset_reference).  If
  /// the mirror's reference is still `dropped` (it has taken no keyframe since), the mirror goes back too, so that
  /// the messages still to come are pinned as the stage will decide them.  Messages already batched were decided
  /// against `dropped`: the stage keeps its own selector for them (GraphStage::on_coalesced), and at most some of
  /// them that it would have taken as keyframes reach it merged into a later one (a keyframe a little later).
  void keyframe_dropped(const std::string& source, const SE3& dropped, const std::optional<SE3>& reference);

  /// Stage thread, before any event: a restored graph stage (its state directory) hands each body's last odometry
  /// message and keyframe selector to the mirror, so that the next messages are pinned and merged as the stage will
  /// decide them, exactly as if the daemon had not stopped.
  void resume(const std::string& source, const KeyframeSelector& selector, int64_t last_utime, const SE3& last_pose,
              const Matrix6& last_covariance);

  /// Stage thread: a forgotten body (GraphStage::forget) starts afresh.
  void forget(const std::string& source);

  int64_t coalesced() const;     // messages merged into a later one
  int64_t out_of_order() const;  // messages at or before their body's newest time, dropped here
  int64_t waiting() const;       // messages in batches the stage has not taken yet (after merging)

 private:
  struct Body {
    KeyframeSelector selector;
    bool has_last = false;
    int64_t last_utime = 0;
    SE3 last_pose;
    Matrix6 last_covariance = Matrix6::Zero();
    std::deque<Batch> batches;          // queued tokens' batches, oldest first
    bool open = false;                  // batches.back() still takes messages
    std::vector<int64_t> waiting_times;  // of sightings and loops ahead of the odometry, ascending (bounded)
  };
  Entry make_entry(const Body& b, const Odometry& o, KeyframeDecision d, bool pinned) const;

  OdometryCoalescerOptions options_;
  mutable std::mutex mutex_;
  std::map<std::string, Body> bodies_;
  int64_t coalesced_ = 0, out_of_order_ = 0, waiting_ = 0;
};

}  // namespace sextant::engine
