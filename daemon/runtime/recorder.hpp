#pragma once
// Records received messages into an LCM log (lcm-logger's format) from its own thread, so disk never stalls the
// LCM thread.  Bounded: when the writer falls behind, records are dropped and counted.  `close` writes what is
// queued and flushes.
// An existing file is never overwritten (a restart with the same --record used to destroy the recording of the run
// before): the recording goes to the first free name among PATH, STEM-1.EXT, STEM-2.EXT, ... (`path()`).
// A write that fails (disk full) stops the recording, logged once and counted (`failed`), never the daemon.
#include "daemon/runtime/bounded_queue.hpp"
#include "daemon/runtime/lcm_log.hpp"

#include <atomic>
#include <memory>
#include <thread>

namespace sextant::runtime {

/// The first of PATH, STEM-1.EXT, STEM-2.EXT, ... that does not exist, created empty (O_EXCL, so two recorders never
/// share a file); throws std::runtime_error when none can be created.
std::string create_unused(const std::string& path);

class Recorder {
 public:
  Recorder(const std::string& path, size_t capacity);
  ~Recorder();
  void record(LogRecord record);
  void close();
  const std::string& path() const { return path_; }
  int64_t written() const { return written_.load(); }
  int64_t dropped() const { return static_cast<int64_t>(queue_.dropped()) + failed_dropped_.load(); }
  bool failed() const { return failed_.load(); }

 private:
  std::string path_;
  std::unique_ptr<LogWriter> writer_;
  BoundedQueue<LogRecord> queue_;
  std::atomic<int64_t> written_{0}, failed_dropped_{0};
  std::atomic<bool> failed_{false};
  std::thread thread_;
};

}  // namespace sextant::runtime
