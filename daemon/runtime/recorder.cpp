#include "daemon/runtime/recorder.hpp"

namespace sextant::runtime {

Recorder::Recorder(const std::string& path, size_t capacity) : writer_(path), queue_(capacity) {
  thread_ = std::thread([this] {
    int since_flush = 0;
    while (auto r = queue_.pop()) {
      writer_.write_raw(r->timestamp, r->channel, r->data.data(), r->data.size());
      ++written_;
      if (++since_flush >= 64 || queue_.size() == 0) {
        writer_.flush();
        since_flush = 0;
      }
    }
    writer_.flush();
  });
}

Recorder::~Recorder() { close(); }

void Recorder::record(LogRecord record) { queue_.try_push(std::move(record)); }

void Recorder::close() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

}  // namespace sextant::runtime
