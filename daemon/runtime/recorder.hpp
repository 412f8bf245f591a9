#pragma once
// Records received messages into an LCM log (lcm-logger's format) from its own thread, so disk never stalls the
// LCM thread.  Bounded: when the writer falls behind, records are dropped and counted.  `close` writes what is
// queued and flushes.
#include "daemon/runtime/bounded_queue.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <atomic>
#include <thread>

namespace sextant::runtime {

class Recorder {
 public:
  Recorder(const std::string& path, size_t capacity);
  ~Recorder();
  void record(LogRecord record);
  void close();
  int64_t written() const { return written_.load(); }
  int64_t dropped() const { return static_cast<int64_t>(queue_.dropped()); }

 private:
  LogWriter writer_;
  BoundedQueue<LogRecord> queue_;
  std::atomic<int64_t> written_{0};
  std::thread thread_;
};

}  // namespace sextant::runtime
