#include "daemon/runtime/pipelined_lanes.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <exception>

namespace sextant::runtime {

namespace {

/// Events handed to the worker at once: one lock per batch, not per event.
constexpr size_t kBatch = 64;

bool before(const StageCapture& a, const StageCapture& b) {
  return a.phase != b.phase ? a.phase < b.phase : a.stage < b.stage;
}

}  // namespace

PipelinedLanes::PipelinedLanes(std::vector<char> on_worker, Deliver deliver, size_t capacity)
    : on_worker_(std::move(on_worker)), deliver_(std::move(deliver)), capacity_(std::max<size_t>(capacity, kBatch)) {}

void PipelinedLanes::attach(std::vector<StageHost*> hosts) {
  hosts_ = std::move(hosts);
  worker_ = std::thread([this] { worker_loop(); });
}

PipelinedLanes::~PipelinedLanes() { stop_worker(); }

void PipelinedLanes::stop_worker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  to_worker_.notify_one();
  if (worker_.joinable()) worker_.join();
}

engine::Emit PipelinedLanes::emit_into(size_t stage) {
  return [this, stage](engine::Output o) {
    target_[on_worker_[stage] ? 1 : 0]->push_back(StageCapture{1, stage, std::move(o)});
  };
}

StageHost::ForgetHook PipelinedLanes::forgot_into(size_t stage) {
  // A body the intake expired is forgotten before the event (phase 0), as the one-thread lanes forget it at once; one
  // forgotten while handling the event (its clock re-synchronised) in order with the event's outputs.
  return [this, stage](const std::string& body) {
    const int side = on_worker_[stage] ? 1 : 0;
    target_[side]->push_back(StageCapture{forgetting_expired_[side] ? 0 : 1, stage, StageCapture::Forgot{body}});
  };
}

void PipelinedLanes::run_group(InFlight& item, bool worker) {
  const int side = worker ? 1 : 0;
  target_[side] = worker ? &item.worker : &item.caller;
  forgetting_expired_[side] = true;
  for (const std::string& body : item.forget)
    for (size_t i = 0; i < hosts_.size(); ++i)
      if ((on_worker_[i] != 0) == worker) hosts_[i]->forget(body);
  forgetting_expired_[side] = false;
  for (size_t i = 0; i < hosts_.size(); ++i) {
    if ((on_worker_[i] != 0) != worker || !hosts_[i]->stage().accepts(item.event.event)) continue;
    const auto t0 = std::chrono::steady_clock::now();
    hosts_[i]->handle(item.event);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    target_[side]->push_back(StageCapture{1, i, StageCapture::Handled{ms}});
  }
}

void PipelinedLanes::route(QueuedEvent event) {
  auto item = std::make_unique<InFlight>();
  item->event = std::move(event);
  item->forget = std::move(forget_next_);
  forget_next_.clear();
  run_group(*item, false);
  batch_.push_back(item.get());
  in_flight_.push_back(std::move(item));
  if (batch_.size() >= kBatch) hand_over();
  // Full: wait until half of them are done (not for each one: a wake-up per event would cost more than the event).
  if (in_flight_.size() >= capacity_) wait_for(*in_flight_[in_flight_.size() - capacity_ / 2]);
  deliver_done();
}

void PipelinedLanes::hand_over() {
  if (batch_.empty()) return;
  {
    std::lock_guard lock(mutex_);
    queue_.insert(queue_.end(), batch_.begin(), batch_.end());
  }
  batch_.clear();
  to_worker_.notify_one();
}

void PipelinedLanes::worker_loop() {
  for (;;) {
    std::deque<InFlight*> taken;
    {
      std::unique_lock lock(mutex_);
      to_worker_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopped, nothing left
      taken.swap(queue_);
    }
    for (InFlight* item : taken) {
      try {
        run_group(*item, true);
      } catch (const std::exception& e) {  // a capture that could not be stored: the event's outputs are lost
        spdlog::error("replay worker: {}", e.what());
      } catch (...) {  // nothing leaves the thread
        spdlog::error("replay worker: an exception that is not a std::exception");
      }
      item->done.store(true);
      if (awaited_.load() == item) {
        std::lock_guard lock(mutex_);
        to_caller_.notify_one();
      }
    }
  }
}

void PipelinedLanes::wait_for(InFlight& item) {
  if (item.done.load()) return;
  hand_over();
  std::unique_lock lock(mutex_);
  awaited_.store(&item);
  to_caller_.wait(lock, [&] { return item.done.load(); });
  awaited_.store(nullptr);
}

void PipelinedLanes::deliver_done() {
  while (!in_flight_.empty() && in_flight_.front()->done.load()) {
    deliver(*in_flight_.front());
    in_flight_.pop_front();
  }
}

void PipelinedLanes::deliver(InFlight& item) {
  std::vector<StageCapture> all;
  all.reserve(item.caller.size() + item.worker.size());
  std::merge(std::make_move_iterator(item.caller.begin()), std::make_move_iterator(item.caller.end()),
             std::make_move_iterator(item.worker.begin()), std::make_move_iterator(item.worker.end()),
             std::back_inserter(all), before);
  for (StageCapture& c : all) deliver_(c);
}

void PipelinedLanes::settle() {
  if (in_flight_.empty()) return;
  wait_for(*in_flight_.back());
  deliver_done();
}

void PipelinedLanes::finish() {
  settle();
  stop_worker();
  // Both groups on this thread now, in stage order, into one list.
  InFlight last;
  last.forget = std::move(forget_next_);
  forget_next_.clear();
  target_[0] = target_[1] = &last.caller;
  for (const std::string& body : last.forget)
    for (StageHost* host : hosts_) host->forget(body);
  for (StageHost* host : hosts_) host->finish();
  for (StageCapture& c : last.caller) deliver_(c);
}

}  // namespace sextant::runtime
