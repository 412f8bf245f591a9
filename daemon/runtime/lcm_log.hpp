#pragma once
// LCM log files (lcm-logger's format) for recording, simulation, conversion and replay.
// Each event has a channel, a timestamp and the encoded bytes; `timestamp` is whatever the writer chose:
// lcm-logger stores wall-clock receive time, sextant's own writers store the message utime.
//
// The format (LCM's eventlog.c; every integer big-endian), one event after another:
//   int32 sync word 0xEDA1DA01, int64 event number, int64 timestamp, int32 channel length, int32 data length,
//   channel bytes (no NUL), data bytes.
// The reader is our own over that format: liblcm 1.3.1's callocs `datalen + 1` (a datalen of 0x7fffffff overflows
// and it freads into NULL) and stops silently at the first corrupt header.  Ours checks every length against the
// bytes left in the file, accepts an event only when the next sync word (or the end of the file) follows it, and
// otherwise resynchronises on the next sync word, counting what it skipped (LogDamage).
#include "daemon/runtime/wire_layout.hpp"

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

/// What a reader found wrong in a log.  A damaged log had corrupt events (resynchronised over); a truncated tail
/// alone (the last event cut short, as a killed recorder leaves it) is not damage.
struct LogDamage {
  int64_t bad_events = 0;                   // event headers found corrupt (each followed by a resynchronisation)
  int64_t skipped_bytes = 0;                // bytes skipped while resynchronising (not part of any good event)
  int64_t missing_event_numbers = 0;        // gaps in the event numbers of the good events (events lost in damage)
  int64_t truncated_tail_bytes = 0;         // an incomplete last event
  std::vector<std::string> first_problems;  // the first few, each "byte OFFSET: what"
  bool damaged() const { return bad_events > 0 || skipped_bytes > 0; }
  /// One line: "3 corrupt events, 1234 bytes skipped, ... (first: byte 52: data length ...)"; empty when clean.
  std::string summary() const;
};

class LogWriter {
 public:
  /// Opens `path` (truncating it; with `exclusive`, failing when it exists); throws std::runtime_error naming the
  /// path when it cannot.
  explicit LogWriter(const std::string& path, bool exclusive = false);
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

/// Reads events from bytes in memory or from a file, checking every size (see the top of this file).
class LogReader {
 public:
  /// Opens `path` for reading; throws std::runtime_error naming the path when it cannot.
  explicit LogReader(const std::string& path);
  /// Reads from a copy of `bytes` (fuzzing, tests).
  static LogReader from_bytes(std::vector<uint8_t> bytes);
  ~LogReader();
  LogReader(LogReader&&) noexcept;
  LogReader& operator=(LogReader&&) noexcept;

  /// The next good event, or nullopt at the end of the file.  Corrupt events are skipped and counted in `damage`.
  std::optional<LogRecord> next();
  const LogDamage& damage() const { return damage_; }
  /// Where the event `next` returned last starts in the file (bytes), for reading it again after `seek`.
  int64_t last_offset() const { return last_offset_; }
  /// The next call of `next` reads from byte `offset` on (a place `last_offset` gave, to read an event again).
  void seek(int64_t offset) {
    pos_ = offset;
    last_event_number_.reset();
  }

  /// Every good event of the file, in file order; what was skipped goes into `damage` when given.
  static std::vector<LogRecord> read_all(const std::string& path, LogDamage* damage = nullptr);

 private:
  struct Source;
  explicit LogReader(std::unique_ptr<Source> source);
  std::optional<int64_t> find_sync(int64_t from);
  void problem(int64_t at, const std::string& what);

  std::unique_ptr<Source> source_;
  int64_t pos_ = 0, last_offset_ = 0;
  std::optional<int64_t> last_event_number_;
  LogDamage damage_;
};

/// Decodes `data` as `Msg`; false when the bytes are not a valid Msg (wrong fingerprint, truncated, or lengths that
/// do not fit: see safe_decode).  Never throws.
template <class Msg>
bool decode_message(const std::vector<uint8_t>& data, Msg& msg) {
  return !safe_decode(data.data(), data.size(), msg);
}

}  // namespace sextant::runtime
