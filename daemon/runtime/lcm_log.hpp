#pragma once
// LCM log files (lcm-logger's format) for recording, simulation, conversion and replay.
// Each event has a channel, a timestamp and the encoded bytes; `timestamp` is whatever the writer chose:
// lcm-logger stores wall-clock receive time, sextant's own writers store the message utime.
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sextant::runtime {

struct LogRecord {
  int64_t timestamp = 0;  // microseconds
  std::string channel;
  std::vector<uint8_t> data;
};

class LogWriter {
 public:
  /// Opens (truncates) `path`; throws std::runtime_error naming the path when it cannot.
  explicit LogWriter(const std::string& path);
  void write_raw(int64_t timestamp, const std::string& channel, const void* data, size_t size);
  /// Encodes an lcm-gen message and writes it with `timestamp` (normally the message's utime).
  template <class Msg>
  void write(int64_t timestamp, const std::string& channel, const Msg& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    if (msg.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0)
      throw std::runtime_error("cannot encode message for channel " + channel);
    write_raw(timestamp, channel, buf.data(), buf.size());
  }
  void flush();
  const std::string& path() const { return path_; }
  int64_t events_written() const { return written_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  int64_t event_number_ = 0;
  int64_t written_ = 0;
};

class LogReader {
 public:
  /// Opens `path` for reading; throws std::runtime_error naming the path when it cannot.
  explicit LogReader(const std::string& path);
  /// The next record, or nullopt at the end of the file.
  std::optional<LogRecord> next();
  /// Every record of the file, in file order.
  static std::vector<LogRecord> read_all(const std::string& path);

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
};

/// Decodes `data` as `Msg`; false when the bytes are not a valid Msg (wrong fingerprint or truncated).
template <class Msg>
bool decode_message(const std::vector<uint8_t>& data, Msg& msg) {
  return msg.decode(data.data(), 0, static_cast<int>(data.size())) >= 0;
}

}  // namespace sextant::runtime
