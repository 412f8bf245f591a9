#pragma once
// Per-input-channel counters for the status channel: received, decoded, rejected by reason, dropped, lost.
// Thread-safe; the LCM thread writes, the status thread reads.
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace sextant::runtime {

struct ChannelCounts {
  int64_t received = 0;
  int64_t decoded = 0;
  int64_t rejected = 0;
  int64_t dropped = 0;
  int64_t lost = 0;  // gaps in the senders' sequence numbers (sequence_gaps.hpp)
  std::map<std::string, int64_t> reasons;
  std::string last_error;
  /// `lost` by sender: at most kMaxLostSenders names; a sender beyond them is summed under kOtherSenders.
  std::map<std::string, int64_t> lost_by_sender;
  static constexpr size_t kMaxLostSenders = 64;
  static inline const std::string kOtherSenders = "*";
};

class ChannelStats {
 public:
  /// Lists a channel with zero counts (input channels show up on the status channel before their first message).
  void add(const std::string& channel);
  void received(const std::string& channel);
  void decoded(const std::string& channel);
  void rejected(const std::string& channel, const std::string& reason, const std::string& message);
  void dropped(const std::string& channel, int64_t n = 1);
  /// `n` messages of `sender` never arrived on `channel`.
  void lost(const std::string& channel, const std::string& sender, int64_t n);
  std::map<std::string, ChannelCounts> snapshot() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, ChannelCounts> channels_;
};

}  // namespace sextant::runtime
