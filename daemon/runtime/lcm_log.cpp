#include "daemon/runtime/lcm_log.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <sstream>
#include <utility>

namespace sextant::runtime {
namespace {

constexpr uint8_t kSync[4] = {0xED, 0xA1, 0xDA, 0x01};
constexpr int64_t kHeaderBytes = 28;         // sync, event number, timestamp, channel length, data length
constexpr int32_t kMaxChannelLength = 1000;  // liblcm's own bound (LCM channels are at most 63 characters)
constexpr size_t kMaxProblemsKept = 8;

uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}
uint64_t be64(const uint8_t* p) { return (uint64_t{be32(p)} << 32) | be32(p + 4); }
bool is_sync(const uint8_t* p) { return std::memcmp(p, kSync, 4) == 0; }

}  // namespace

// The bytes of a log: a file read through a window (pread), or a buffer in memory.
struct LogReader::Source {
  int fd = -1;
  int64_t size = 0;
  std::vector<uint8_t> window;  // the file's bytes [window_start, window_start + window.size()), or all of them
  int64_t window_start = 0;
  bool in_memory = false;

  ~Source() {
    if (fd >= 0) ::close(fd);
  }

  // Pointer to the bytes [pos, pos + n); nullptr when the file has fewer.
  const uint8_t* view(int64_t pos, int64_t n) {
    if (pos < 0 || n < 0 || pos + n > size) return nullptr;
    if (pos >= window_start && pos + n <= window_start + static_cast<int64_t>(window.size()))
      return window.data() + (pos - window_start);
    if (in_memory) return nullptr;
    const int64_t len = std::min(size - pos, std::max<int64_t>(n, int64_t{1} << 20));
    window.resize(static_cast<size_t>(len));
    window_start = pos;
    int64_t got = 0;
    while (got < len) {
      const ssize_t r = ::pread(fd, window.data() + got, static_cast<size_t>(len - got), pos + got);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) break;
      got += r;
    }
    if (got < len) {  // the file shrank under us: what is gone is the end of the file
      window.resize(static_cast<size_t>(got));
      size = pos + got;
      return got >= n ? window.data() : nullptr;
    }
    return window.data();
  }
};

std::string LogDamage::summary() const {
  if (!damaged() && truncated_tail_bytes == 0) return {};
  std::ostringstream s;
  if (damaged()) {
    s << bad_events << " corrupt event header(s), " << skipped_bytes << " bytes skipped";
    if (missing_event_numbers > 0) s << ", about " << missing_event_numbers << " events lost (event-number gaps)";
  }
  if (truncated_tail_bytes > 0)
    s << (damaged() ? "; " : "") << "last event truncated (" << truncated_tail_bytes << " bytes)";
  if (!first_problems.empty()) s << " (first: " << first_problems.front() << ")";
  return s.str();
}

LogWriter::LogWriter(const std::string& path, bool exclusive) : path_(path) {
  if (exclusive) {
    // Created here so that an existing file is never truncated (LogFile's "w" would); LogFile then opens it empty.
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) throw std::runtime_error("cannot create log file " + path + ": " + std::strerror(errno));
    ::close(fd);
  }
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good())
    throw std::runtime_error("cannot open log file for writing: " + path + ": " + std::strerror(errno));
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

LogReader::LogReader(std::unique_ptr<Source> source) : source_(std::move(source)) {}

LogReader::LogReader(const std::string& path) : source_(std::make_unique<Source>()) {
  source_->fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (source_->fd < 0 || ::fstat(source_->fd, &st) != 0)
    throw std::runtime_error("cannot open log file for reading: " + path + ": " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw std::runtime_error("cannot read log file " + path + ": it is a directory");
  source_->size = static_cast<int64_t>(st.st_size);
}

LogReader LogReader::from_bytes(std::vector<uint8_t> bytes) {
  auto s = std::make_unique<Source>();
  s->in_memory = true;
  s->size = static_cast<int64_t>(bytes.size());
  s->window = std::move(bytes);
  return LogReader(std::move(s));
}

LogReader::~LogReader() = default;
LogReader::LogReader(LogReader&&) noexcept = default;
LogReader& LogReader::operator=(LogReader&&) noexcept = default;

void LogReader::problem(int64_t at, const std::string& what) {
  if (damage_.first_problems.size() < kMaxProblemsKept)
    damage_.first_problems.push_back("byte " + std::to_string(at) + ": " + what);
}

std::optional<int64_t> LogReader::find_sync(int64_t from) {
  constexpr int64_t kChunk = 1 << 16;
  for (int64_t p = from; p + 4 <= source_->size; p += kChunk) {
    const int64_t n = std::min(kChunk + 3, source_->size - p);
    const uint8_t* b = source_->view(p, n);
    if (b == nullptr) return std::nullopt;
    const uint8_t* hit = std::search(b, b + n, kSync, kSync + 4);
    if (hit != b + n) return p + (hit - b);
  }
  return std::nullopt;
}

std::optional<LogRecord> LogReader::next() {
  int64_t skipped_since_good = 0;
  // Skips the bad event at pos_ (described by `what`) up to the next sync word after it, or the end of the file.
  auto resync = [&](const std::string& what) {
    ++damage_.bad_events;
    problem(pos_, what);
    const int64_t to = find_sync(pos_ + 1).value_or(source_->size);
    damage_.skipped_bytes += to - pos_;
    skipped_since_good += to - pos_;
    pos_ = to;
  };
  while (pos_ < source_->size) {
    const int64_t left = source_->size - pos_;
    if (left < kHeaderBytes) {
      const uint8_t* b = source_->view(pos_, left);
      if (b != nullptr && std::memcmp(b, kSync, static_cast<size_t>(std::min<int64_t>(left, 4))) == 0) {
        damage_.truncated_tail_bytes += left;
        pos_ = source_->size;
        return std::nullopt;
      }
      resync("no sync word (" + std::to_string(left) + " bytes at the end of the file)");
      continue;
    }
    const uint8_t* h = source_->view(pos_, kHeaderBytes);
    if (h == nullptr) break;
    if (!is_sync(h)) {
      resync("no sync word where an event should start");
      continue;
    }
    const auto event_number = static_cast<int64_t>(be64(h + 4));
    const auto timestamp = static_cast<int64_t>(be64(h + 12));
    const auto channel_len = static_cast<int32_t>(be32(h + 20));
    const auto data_len = static_cast<int32_t>(be32(h + 24));
    if (channel_len <= 0 || channel_len >= kMaxChannelLength) {
      resync("channel length " + std::to_string(channel_len) + " outside [1, " + std::to_string(kMaxChannelLength - 1) +
             "]");
      continue;
    }
    if (data_len < 0) {
      resync("negative data length " + std::to_string(data_len));
      continue;
    }
    const int64_t end = pos_ + kHeaderBytes + channel_len + int64_t{data_len};
    if (end > source_->size) {
      if (!find_sync(pos_ + 1)) {  // nothing follows: the last event was cut short
        damage_.truncated_tail_bytes += left;
        pos_ = source_->size;
        return std::nullopt;
      }
      resync("data length " + std::to_string(data_len) + " exceeds the " + std::to_string(left - kHeaderBytes) +
             " bytes left in the file");
      continue;
    }
    if (end < source_->size) {
      const int64_t n = std::min<int64_t>(4, source_->size - end);
      const uint8_t* after = source_->view(end, n);
      if (after == nullptr || std::memcmp(after, kSync, static_cast<size_t>(n)) != 0) {
        resync("event of channel length " + std::to_string(channel_len) + " and data length " +
               std::to_string(data_len) + " is not followed by a sync word (a corrupt length or a damaged next event)");
        continue;
      }
    }
    const uint8_t* body = source_->view(pos_ + kHeaderBytes, channel_len + int64_t{data_len});
    if (body == nullptr) break;
    LogRecord r;
    r.timestamp = timestamp;
    r.channel.assign(reinterpret_cast<const char*>(body), static_cast<size_t>(channel_len));
    r.data.assign(body + channel_len, body + channel_len + data_len);
    // Event numbers count up by one: a gap across skipped bytes tells how many events the damage took (bounded by
    // what the skipped bytes could hold, in case the number itself is what was damaged).
    if (last_event_number_ && skipped_since_good > 0 && *last_event_number_ >= 0 &&
        *last_event_number_ < INT64_MAX - 1 && event_number > *last_event_number_ + 1)
      damage_.missing_event_numbers +=
          std::min(event_number - *last_event_number_ - 1, skipped_since_good / (kHeaderBytes + 1) + 1);
    last_event_number_ = event_number;
    last_offset_ = std::exchange(pos_, end);
    return r;
  }
  return std::nullopt;
}

std::vector<LogRecord> LogReader::read_all(const std::string& path, LogDamage* damage) {
  LogReader reader(path);
  std::vector<LogRecord> out;
  while (auto r = reader.next()) out.push_back(std::move(*r));
  if (damage != nullptr) *damage = reader.damage();
  return out;
}

}  // namespace sextant::runtime
