#include "daemon/runtime/stage_runner.hpp"

namespace sextant::runtime {

StageRunner::StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit)
    : stage_(stage), emit_(std::move(emit)), queue_(queue_capacity), counters_(stage.counters()) {}

StageRunner::~StageRunner() { drain_and_stop(); }

bool StageRunner::offer(const QueuedEvent& event) {
  return stage_.offer(event.event, [&] { return queue_.try_push(event); });
}

void StageRunner::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
}

void StageRunner::drain_and_stop() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

void StageRunner::loop() {
  while (auto item = queue_.pop()) {
    stage_.handle(item->event, emit_);
    const auto done = std::chrono::steady_clock::now();
    latency_.add(std::chrono::duration<double, std::milli>(done - item->received).count());
    ++processed_;
    auto counters = stage_.counters();
    std::lock_guard lock(counters_mutex_);
    counters_ = std::move(counters);
  }
  stage_.finish(emit_);
  auto counters = stage_.counters();
  std::lock_guard lock(counters_mutex_);
  counters_ = std::move(counters);
}

StageStatus StageRunner::status() const {
  StageStatus s;
  s.name = std::string(stage_.name());
  s.queue_depth = queue_.size();
  s.queue_capacity = queue_.capacity();
  s.processed = processed_.load();
  s.dropped = static_cast<int64_t>(queue_.dropped());
  s.latency = latency_.summary();
  std::lock_guard lock(counters_mutex_);
  s.counters = counters_;
  return s;
}

}  // namespace sextant::runtime
