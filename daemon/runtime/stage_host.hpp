#pragma once
// One engine stage and what surrounds every call into it, the same on a daemon's stage thread and in a synchronous
// replay: a body is forgotten by the stage and then by whoever keeps per-body output state (the publisher, through
// the forget hook, after the stage's earlier outputs); an event whose body's clock was re-synchronised first forgets
// that body; nothing the stage throws escapes (engine/guarded_handle.hpp: handle, then recover), and every failure is
// counted, kept as the last one, and logged (the first ten, then every power of two).
// Not thread-safe, except the counters (atomics) and last_failure (its own lock): the caller drives it from one
// thread at a time.
#include "daemon/engine/stage.hpp"
#include "daemon/runtime/queued_event.hpp"

#include <atomic>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

namespace sextant::runtime {

class StageHost {
 public:
  using ForgetHook = std::function<void(const std::string& body)>;

  StageHost(engine::Stage& stage, engine::Emit emit);
  /// Told of every body the stage forgot, after the stage's earlier outputs (set before the first event).
  void on_forget(ForgetHook hook) { on_forget_ = std::move(hook); }

  /// The stage forgets `body` (Stage::forget), then the forget hook is told.
  void forget(const std::string& body);
  /// Forgets `event.forget_first` when set, then handles the event (failures counted, the stage recovered).
  void handle(const QueuedEvent& event);
  /// End of input: the stage flushes what is pending.
  void finish();
  /// The stage's own counters; nullopt when `counters` threw (counted as a failure).
  std::optional<engine::Counters> stage_counters();
  /// The stage's counters followed by the host's: stage_failures, stage_recoveries, resync_forgets.
  engine::Counters with_host_counters(engine::Counters stage) const;

  engine::Stage& stage() { return stage_; }
  const engine::Stage& stage() const { return stage_; }
  std::string last_failure() const;

 private:
  void count_failure(const std::string& message);

  engine::Stage& stage_;
  engine::Emit emit_;
  ForgetHook on_forget_;
  std::atomic<int64_t> failures_{0}, recoveries_{0}, resync_forgets_{0};
  mutable std::mutex failure_mutex_;
  std::string last_failure_;
};

}  // namespace sextant::runtime
