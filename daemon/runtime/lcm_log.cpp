#include "daemon/runtime/lcm_log.hpp"

#include <cerrno>
#include <cstring>

namespace sextant::runtime {

LogWriter::LogWriter(const std::string& path) : path_(path), log_(std::make_unique<lcm::LogFile>(path, "w")) {
  if (!log_->good()) throw std::runtime_error("cannot open log file for writing: " + path + ": " + std::strerror(errno));
}

void LogWriter::write_raw(int64_t timestamp, const std::string& channel, const void* data, size_t size) {
  lcm::LogEvent ev{};
  ev.eventnum = event_number_++;
  ev.timestamp = timestamp;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(size);
  ev.data = const_cast<void*>(data);
  if (log_->writeEvent(&ev) != 0) throw std::runtime_error("cannot write to log file " + path_);
  ++written_;
}

void LogWriter::flush() { std::fflush(log_->getFilePtr()); }

LogReader::LogReader(const std::string& path) : path_(path), log_(std::make_unique<lcm::LogFile>(path, "r")) {
  if (!log_->good()) throw std::runtime_error("cannot open log file for reading: " + path + ": " + std::strerror(errno));
}

std::optional<LogRecord> LogReader::next() {
  const lcm::LogEvent* ev = log_->readNextEvent();
  if (ev == nullptr) return std::nullopt;
  LogRecord r;
  r.timestamp = ev->timestamp;
  r.channel = ev->channel;
  const auto* bytes = static_cast<const uint8_t*>(ev->data);
  r.data.assign(bytes, bytes + ev->datalen);
  return r;
}

std::vector<LogRecord> LogReader::read_all(const std::string& path) {
  LogReader reader(path);
  std::vector<LogRecord> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  return out;
}

}  // namespace sextant::runtime
