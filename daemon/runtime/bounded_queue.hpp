#pragma once
// A bounded multi-producer queue with blocking pop.  When full, `try_push` refuses the new item (the caller
// counts it as dropped): memory stays bounded under overload and what was already accepted keeps its order.
// `close` wakes every waiter; after it, pushes are refused and pops drain what remains, then return nullopt.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <utility>

namespace sextant::runtime {

template <class T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  /// False when the queue is full or closed; the item is not taken.
  bool try_push(T item) {
    {
      std::lock_guard lock(mutex_);
      if (closed_ || items_.size() >= capacity_) {
        ++dropped_;
        return false;
      }
      items_.push_back(std::move(item));
      if (items_.size() > high_water_) high_water_ = items_.size();
    }
    cv_.notify_one();
    return true;
  }

  /// Blocks until an item is available or the queue is closed and empty.
  std::optional<T> pop() {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    return item;
  }

  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

  /// Removes every queued item (a bounded shutdown gives up on them) and returns them.
  std::deque<T> discard() {
    std::lock_guard lock(mutex_);
    return std::exchange(items_, {});
  }

  size_t size() const {
    std::lock_guard lock(mutex_);
    return items_.size();
  }
  size_t capacity() const { return capacity_; }
  size_t dropped() const {
    std::lock_guard lock(mutex_);
    return dropped_;
  }
  size_t high_water() const {
    std::lock_guard lock(mutex_);
    return high_water_;
  }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<T> items_;
  bool closed_ = false;
  size_t dropped_ = 0;
  size_t high_water_ = 0;
};

}  // namespace sextant::runtime
