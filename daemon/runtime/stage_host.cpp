#include "daemon/runtime/stage_host.hpp"

#include "daemon/engine/guarded_handle.hpp"

#include <spdlog/spdlog.h>

namespace sextant::runtime {

StageHost::StageHost(engine::Stage& stage, engine::Emit emit) : stage_(stage), emit_(std::move(emit)) {}

void StageHost::count_failure(const std::string& message) {
  const int64_t n = ++failures_;
  if (n <= 10 || (n & (n - 1)) == 0) spdlog::error("stage '{}': {} ({} failure(s) so far)", stage_.name(), message, n);
  std::lock_guard lock(failure_mutex_);
  last_failure_ = message;
}

std::string StageHost::last_failure() const {
  std::lock_guard lock(failure_mutex_);
  return last_failure_;
}

void StageHost::forget(const std::string& body) {
  if (auto thrown = engine::call_guarded([&] { stage_.forget(body); })) count_failure("forget: " + *thrown);
  if (on_forget_)
    if (auto thrown = engine::call_guarded([&] { on_forget_(body); })) count_failure("forget: " + *thrown);
}

void StageHost::handle(const QueuedEvent& event) {
  // A body whose clock jumped: what the stage keeps of it belongs to the old clock and would refuse every message of
  // the new one, so it starts afresh here, in order with the messages before.
  if (!event.forget_first.empty()) {
    forget(event.forget_first);
    ++resync_forgets_;
  }
  if (auto failure = engine::handle_guarded(stage_, event.event, emit_)) {
    count_failure(failure->message);
    if (failure->recovered)
      ++recoveries_;
    else
      count_failure(failure->recover_message);
  }
}

void StageHost::finish() {
  if (auto thrown = engine::call_guarded([&] { stage_.finish(emit_); })) count_failure("finish: " + *thrown);
}

std::optional<engine::Counters> StageHost::stage_counters() {
  engine::Counters counters;
  if (auto thrown = engine::call_guarded([&] { counters = stage_.counters(); })) {
    count_failure("counters: " + *thrown);
    return std::nullopt;
  }
  return counters;
}

engine::Counters StageHost::with_host_counters(engine::Counters stage) const {
  stage.push_back({"stage_failures", failures_.load()});
  stage.push_back({"stage_recoveries", recoveries_.load()});
  stage.push_back({"resync_forgets", resync_forgets_.load()});
  return stage;
}

}  // namespace sextant::runtime
