#include "daemon/runtime/channel_stats.hpp"

namespace sextant::runtime {

void ChannelStats::add(const std::string& channel) {
  std::lock_guard lock(mutex_);
  channels_[channel];
}

void ChannelStats::received(const std::string& channel) {
  std::lock_guard lock(mutex_);
  ++channels_[channel].received;
}

void ChannelStats::decoded(const std::string& channel) {
  std::lock_guard lock(mutex_);
  ++channels_[channel].decoded;
}

void ChannelStats::rejected(const std::string& channel, const std::string& reason, const std::string& message) {
  std::lock_guard lock(mutex_);
  auto& c = channels_[channel];
  ++c.rejected;
  ++c.reasons[reason];
  c.last_error = message;
}

void ChannelStats::dropped(const std::string& channel, int64_t n) {
  std::lock_guard lock(mutex_);
  channels_[channel].dropped += n;
}

void ChannelStats::lost(const std::string& channel, const std::string& sender, int64_t n) {
  std::lock_guard lock(mutex_);
  auto& c = channels_[channel];
  c.lost += n;
  // Bounded: the first kMaxLostSenders senders that lose anything are named, the rest share one entry.
  auto it = c.lost_by_sender.find(sender);
  if (it == c.lost_by_sender.end() && c.lost_by_sender.size() >= ChannelCounts::kMaxLostSenders)
    it = c.lost_by_sender.try_emplace(ChannelCounts::kOtherSenders, 0).first;
  else if (it == c.lost_by_sender.end())
    it = c.lost_by_sender.emplace(sender, 0).first;
  it->second += n;
}

std::map<std::string, ChannelCounts> ChannelStats::snapshot() const {
  std::lock_guard lock(mutex_);
  return channels_;
}

}  // namespace sextant::runtime
