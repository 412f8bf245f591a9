#include "daemon/runtime/recorder.hpp"

#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace sextant::runtime {

std::string create_unused(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string stem = (p.parent_path() / p.stem()).string(), ext = p.extension().string();
  for (int i = 0; i < 10000; ++i) {
    const std::string candidate = i == 0 ? path : stem + "-" + std::to_string(i) + ext;
    const int fd = ::open(candidate.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return candidate;
    }
    if (errno != EEXIST) throw std::runtime_error("cannot create " + candidate + ": " + std::strerror(errno));
  }
  throw std::runtime_error("cannot find an unused name next to " + path + " (10000 taken)");
}

Recorder::Recorder(const std::string& path, size_t capacity)
    : path_(create_unused(path)), writer_(std::make_unique<LogWriter>(path_)), queue_(capacity) {
  thread_ = std::thread([this] {
    int since_flush = 0;
    while (auto r = queue_.pop()) {
      if (failed_.load()) {
        ++failed_dropped_;
        continue;
      }
      try {
        writer_->write_raw(r->timestamp, r->channel, r->data.data(), r->data.size());
        ++written_;
        if (++since_flush >= 64 || queue_.size() == 0) {
          writer_->flush();
          since_flush = 0;
        }
      } catch (const std::exception& e) {
        spdlog::error("recording to {} stopped: {}", path_, e.what());
        failed_ = true;
        ++failed_dropped_;
      }
    }
    writer_->flush();
  });
}

Recorder::~Recorder() { close(); }

void Recorder::record(LogRecord record) { queue_.try_push(std::move(record)); }

void Recorder::close() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

}  // namespace sextant::runtime
