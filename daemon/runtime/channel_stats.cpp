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

void ChannelStats::lost(const std::string& channel, int64_t n) {
  std::lock_guard lock(mutex_);
  channels_[channel].lost += n;
}

std::map<std::string, ChannelCounts> ChannelStats::snapshot() const {
  std::lock_guard lock(mutex_);
  return channels_;
}

}  // namespace sextant::runtime
