#include "daemon/runtime/stage_runner.hpp"

#include "daemon/engine/guarded_handle.hpp"

#include <spdlog/spdlog.h>

namespace sextant::runtime {

StageRunner::StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit,
                         std::optional<OdometryBatcherOptions> batching)
    : stage_(stage), emit_(std::move(emit)), queue_(queue_capacity),
      batcher_(batching ? std::make_unique<OdometryBatcher>(*batching) : nullptr), latency_(4096, kLatencyWindowS),
      counters_(stage.counters()) {}

StageRunner::~StageRunner() { drain_and_stop(); }

bool StageRunner::offer(const QueuedEvent& event) {
  if (!batcher_) return queue_.try_push(event);
  return batcher_->offer(
      event, [&](const QueuedEvent& e) { return queue_.try_push(e); },
      [&](const OdometryBatcher::Token& t) { return queue_.try_push(t); });
}

void StageRunner::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
}

void StageRunner::drain_and_stop() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

int64_t StageRunner::drain_and_stop(std::chrono::steady_clock::time_point deadline) {
  queue_.close();
  while (thread_.joinable() && queue_.size() > 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  int64_t left = 0;
  for (const Slot& slot : queue_.discard()) {
    if (const auto* token = std::get_if<OdometryBatcher::Token>(&slot)) left += static_cast<int64_t>(batcher_->take(*token).size());
    else ++left;
  }
  drain_discarded_ += left;
  if (thread_.joinable()) thread_.join();
  return left;
}

void StageRunner::count_failure(const std::string& message) {
  const int64_t n = ++failures_;
  // Every failure is counted; the log gets the first ten and then every power of two.
  if (n <= 10 || (n & (n - 1)) == 0) spdlog::error("stage '{}': {} ({} failure(s) so far)", stage_.name(), message, n);
  std::lock_guard lock(counters_mutex_);
  last_failure_ = message;
}

void StageRunner::forget_now(const std::string& source) {
  if (auto thrown = engine::call_guarded([&] { stage_.forget(source); })) count_failure("forget: " + *thrown);
  if (on_forget_)
    if (auto thrown = engine::call_guarded([&] { on_forget_(source); })) count_failure("forget: " + *thrown);
}

void StageRunner::handle_one(const QueuedEvent& event) {
  // A body whose clock jumped: what the stage keeps of it belongs to the old clock and would refuse every message of
  // the new one, so it starts afresh here, in order with the messages before.
  if (!event.forget_first.empty()) {
    forget_now(event.forget_first);
    ++resync_forgets_;
  }
  if (auto failure = engine::handle_guarded(stage_, event.event, emit_)) {
    count_failure(failure->message);
    if (failure->recovered) ++recoveries_;
    else count_failure(failure->recover_message);
  }
  const auto done = std::chrono::steady_clock::now();
  latency_.add(std::chrono::duration<double, std::milli>(done - event.received).count());
  ++processed_;
}

void StageRunner::loop() {
  while (auto item = queue_.pop()) {
    std::unique_lock stage_lock(stage_mutex_);
    std::unordered_set<std::string> forget;
    {
      std::lock_guard lock(forget_mutex_);
      forget.swap(forget_);
    }
    for (const auto& source : forget) forget_now(source);
    if (const auto* event = std::get_if<QueuedEvent>(&*item)) {
      handle_one(*event);
    } else {
      // A batch's token: the batch is closed now (the body's next odometry opens a new one); its messages one by one.
      for (const QueuedEvent& message : batcher_->take(std::get<OdometryBatcher::Token>(*item))) handle_one(message);
    }
    engine::Counters counters;
    if (auto thrown = engine::call_guarded([&] { counters = stage_.counters(); })) {
      count_failure("counters: " + *thrown);
    } else {
      std::lock_guard lock(counters_mutex_);
      counters_ = std::move(counters);
    }
  }
  std::lock_guard stage_lock(stage_mutex_);
  if (auto thrown = engine::call_guarded([&] { stage_.finish(emit_); })) count_failure("finish: " + *thrown);
  engine::Counters counters;
  if (auto thrown = engine::call_guarded([&] { counters = stage_.counters(); })) {
    count_failure("counters: " + *thrown);
  } else {
    std::lock_guard lock(counters_mutex_);
    counters_ = std::move(counters);
  }
}

StageStatus StageRunner::status() const {
  StageStatus s;
  s.name = std::string(stage_.name());
  s.queue_depth = queue_.size();
  s.queue_capacity = queue_.capacity();
  s.processed = processed_.load();
  s.dropped = static_cast<int64_t>(queue_.dropped()) + (batcher_ ? batcher_->dropped() : 0);
  s.latency = latency_.summary();
  std::lock_guard lock(counters_mutex_);
  s.counters = counters_;
  s.counters.push_back({"stage_failures", failures_.load()});
  s.counters.push_back({"stage_recoveries", recoveries_.load()});
  s.counters.push_back({"resync_forgets", resync_forgets_.load()});
  if (const int64_t d = drain_discarded_.load(); d > 0) s.counters.push_back({"drain_discarded", d});
  if (batcher_) {
    s.counters.push_back({"odometry_coalesced", batcher_->coalesced()});
    s.counters.push_back({"odometry_waiting", batcher_->waiting()});
    s.counters.push_back({"odometry_waiting_dropped", batcher_->dropped()});
  }
  s.last_failure = last_failure_;
  return s;
}

}  // namespace sextant::runtime
