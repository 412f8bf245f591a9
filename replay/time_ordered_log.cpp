#include "replay/time_ordered_log.hpp"

#include <algorithm>
#include <map>
#include <utility>

namespace sextant::tools {

std::optional<int64_t> peek_utime(const std::vector<uint8_t>& data) {
  if (data.size() < 16) return std::nullopt;
  uint64_t v = 0;
  for (size_t i = 8; i < 16; ++i) v = (v << 8) | data[i];  // LCM encodes big-endian
  return static_cast<int64_t>(v);
}

TimeOrderedLog::TimeOrderedLog(std::string path, size_t held_bytes) : path_(std::move(path)), budget_(held_bytes) {
  std::vector<std::pair<int64_t, uint32_t>> keys;
  runtime::LogReader reader(path_);
  while (auto r = reader.next()) keys.emplace_back(replay_stamp(*r), static_cast<uint32_t>(keys.size()));
  damage_ = reader.damage();
  std::stable_sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  rank_.resize(keys.size());
  for (size_t turn = 0; turn < keys.size(); ++turn) rank_[keys[turn].second] = static_cast<uint32_t>(turn);
}

namespace {

size_t bytes_of(const runtime::LogRecord& r) { return r.data.size() + r.channel.size() + sizeof(r); }

}  // namespace

void TimeOrderedLog::for_each(const std::function<void(const runtime::LogRecord&)>& step) {
  read_again_ = 0;
  held_peak_ = 0;
  runtime::LogReader reader(path_);
  std::optional<runtime::LogReader> again;      // opened when a record has to be read a second time
  std::map<uint32_t, runtime::LogRecord> held;  // read before their turn, within the budget
  std::map<uint32_t, int64_t> later;            // read before their turn past the budget: where they start
  size_t held_bytes = 0;
  uint32_t next_turn = 0, index = 0;
  // The records whose turn has come among those read ahead, in turn; false when one has vanished from the file.
  auto catch_up = [&] {
    for (;;) {
      if (auto h = held.find(next_turn); h != held.end()) {
        step(h->second);
        held_bytes -= bytes_of(h->second);
        held.erase(h);
      } else if (auto l = later.find(next_turn); l != later.end()) {
        if (!again) again.emplace(path_);
        again->seek(l->second);
        const auto r = again->next();
        if (!r) return false;
        ++read_again_;
        step(*r);
        later.erase(l);
      } else {
        return true;
      }
      ++next_turn;
    }
  };
  while (auto r = reader.next()) {
    if (index >= rank_.size()) break;  // the file grew since pass 1
    const uint32_t turn = rank_[index++];
    if (turn != next_turn) {
      if (held_bytes + bytes_of(*r) <= budget_) {
        held_bytes += bytes_of(*r);
        held_peak_ = std::max(held_peak_, held_bytes);
        held.emplace(turn, std::move(*r));
      } else {
        later.emplace(turn, reader.last_offset());
      }
      continue;
    }
    step(*r);
    ++next_turn;
    if (!catch_up()) return;
  }
}

}  // namespace sextant::tools
