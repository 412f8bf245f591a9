#include "daemon/runtime/odometry_batcher.hpp"

#include <stdexcept>

namespace sextant::runtime {

class OdometryBatcher::Batch {
 public:
  std::string source;
  std::deque<QueuedEvent> messages;
};

OdometryBatcher::OdometryBatcher(const OdometryBatcherOptions& options) : options_(options) {
  if (options_.max_batch == 0 || options_.max_waiting_per_body == 0 || options_.max_waiting == 0)
    throw std::invalid_argument("odometry batcher: every bound (batch, per body, total) must be at least 1");
}

bool OdometryBatcher::offer(const QueuedEvent& event, const EnqueueEvent& enqueue_event,
                            const EnqueueToken& enqueue_token) {
  std::lock_guard lock(mutex_);
  const auto* o = std::get_if<engine::Odometry>(&event.event);
  if (o == nullptr) {
    if (!enqueue_event(event)) return false;
    // Queued: the body's odometry after it goes into a new batch behind it.
    if (auto it = bodies_.find(engine::event_source(event.event)); it != bodies_.end()) it->second.open.reset();
    return true;
  }
  auto [it, created] = bodies_.try_emplace(o->source);
  Body& b = it->second;
  if (b.waiting >= options_.max_waiting_per_body || waiting_ >= options_.max_waiting) {
    ++dropped_;
    if (created) bodies_.erase(it);
    return false;
  }
  if (b.open && b.open->messages.size() < options_.max_batch) {
    b.open->messages.push_back(event);
    ++coalesced_;
  } else {
    auto batch = std::make_shared<Batch>();
    batch->source = o->source;
    batch->messages.push_back(event);
    if (!enqueue_token(batch)) {
      if (b.waiting == 0) bodies_.erase(it);
      return false;
    }
    b.open = std::move(batch);
  }
  ++b.waiting;
  ++waiting_;
  return true;
}

std::deque<QueuedEvent> OdometryBatcher::take(const Token& token) {
  std::lock_guard lock(mutex_);
  std::deque<QueuedEvent> messages = std::move(token->messages);
  token->messages.clear();
  waiting_ -= messages.size();
  if (auto it = bodies_.find(token->source); it != bodies_.end()) {
    Body& b = it->second;
    if (b.open == token) b.open.reset();
    b.waiting -= messages.size();
    if (b.waiting == 0) bodies_.erase(it);
  }
  return messages;
}

int64_t OdometryBatcher::coalesced() const {
  std::lock_guard lock(mutex_);
  return coalesced_;
}

int64_t OdometryBatcher::waiting() const {
  std::lock_guard lock(mutex_);
  return static_cast<int64_t>(waiting_);
}

int64_t OdometryBatcher::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

}  // namespace sextant::runtime
