#include "daemon/runtime/stage_runner.hpp"

#include <spdlog/spdlog.h>

namespace sextant::runtime {

StageRunner::StageRunner(engine::Stage& stage, size_t queue_capacity, engine::Emit emit,
                         std::optional<OdometryBatcherOptions> batching)
    : host_(stage, std::move(emit)),
      queue_(queue_capacity),
      batcher_(batching ? std::make_unique<OdometryBatcher>(*batching) : nullptr),
      latency_(4096, kLatencyWindowS),
      counters_(stage.counters()) {}

StageRunner::~StageRunner() { drain_and_stop(); }

bool StageRunner::offer(const QueuedEvent& event) {
  if (!batcher_) return queue_.try_push(event);
  return batcher_->offer(
      event, [&](const QueuedEvent& e) { return queue_.try_push(e); },
      [&](const OdometryBatcher::Token& t) { return queue_.try_push(t); });
}

void StageRunner::forget(const std::string& source) {
  const auto push = [&] { return queue_.try_push(ForgetOrder{source}); };
  if (batcher_ ? batcher_->offer_marker(source, push) : push()) return;
  std::lock_guard lock(forget_mutex_);
  forget_.insert(source);
  ++forget_out_of_order_;
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
  while (thread_.joinable() && !finished_.load() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (thread_.joinable() && !finished_.load()) {
    // Still at work at the deadline: a long computation under way ends after its current step (Stage::interrupt).
    host_.stage().interrupt();
    ++drain_interrupted_;
    spdlog::warn("stage '{}': still at work at the drain deadline; interrupted (it ends after its current step)",
                 host_.stage().name());
  }
  int64_t left = 0;
  for (const Slot& slot : queue_.discard()) {
    if (const auto* token = std::get_if<OdometryBatcher::Token>(&slot))
      left += static_cast<int64_t>(batcher_->take(*token).size());
    else if (std::holds_alternative<QueuedEvent>(slot))
      ++left;
  }
  drain_discarded_ += left;
  if (thread_.joinable()) thread_.join();
  return left;
}

void StageRunner::handle_one(const QueuedEvent& event) {
  host_.handle(event);
  const auto done = std::chrono::steady_clock::now();
  latency_.add(std::chrono::duration<double, std::milli>(done - event.received).count());
  ++processed_;
}

void StageRunner::copy_counters() {
  if (auto counters = host_.stage_counters()) {
    std::lock_guard lock(counters_mutex_);
    counters_ = std::move(*counters);
  }
}

void StageRunner::loop() {
  while (auto item = queue_.pop()) {
    std::unique_lock stage_lock(stage_mutex_);
    std::unordered_set<std::string> forget;
    {
      std::lock_guard lock(forget_mutex_);
      forget.swap(forget_);
    }
    for (const auto& source : forget) host_.forget(source);
    if (const auto* event = std::get_if<QueuedEvent>(&*item)) {
      handle_one(*event);
    } else if (const auto* order = std::get_if<ForgetOrder>(&*item)) {
      host_.forget(order->body);
    } else {
      // A batch's token: the batch is closed now (the body's next odometry opens a new one); its messages one by one.
      for (const QueuedEvent& message : batcher_->take(std::get<OdometryBatcher::Token>(*item))) handle_one(message);
    }
    copy_counters();
  }
  std::lock_guard stage_lock(stage_mutex_);
  host_.finish();
  copy_counters();
  finished_ = true;
}

StageStatus StageRunner::status() const {
  StageStatus s;
  s.name = std::string(host_.stage().name());
  s.queue_depth = queue_.size();
  s.queue_capacity = queue_.capacity();
  s.processed = processed_.load();
  s.dropped = static_cast<int64_t>(queue_.dropped()) + (batcher_ ? batcher_->dropped() : 0);
  s.latency = latency_.summary();
  {
    std::lock_guard lock(counters_mutex_);
    s.counters = host_.with_host_counters(counters_);
  }
  if (const int64_t d = drain_discarded_.load(); d > 0) s.counters.push_back({"drain_discarded", d});
  if (const int64_t d = drain_interrupted_.load(); d > 0) s.counters.push_back({"drain_interrupted", d});
  if (const int64_t f = forget_out_of_order_.load(); f > 0) s.counters.push_back({"forget_out_of_order", f});
  if (batcher_) {
    s.counters.push_back({"odometry_coalesced", batcher_->coalesced()});
    s.counters.push_back({"odometry_waiting", batcher_->waiting()});
    s.counters.push_back({"odometry_waiting_dropped", batcher_->dropped()});
  }
  s.last_failure = host_.last_failure();
  return s;
}

}  // namespace sextant::runtime
