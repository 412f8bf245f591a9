#pragma once
// Loss nobody else sees: every sextant message carries its sender's name and a sequence number that increases by
// one per message (per sender and channel).  A gap between consecutive numbers is messages lost before the daemon
// read them: on the network, or dropped by the kernel when the socket's receive buffer overflowed.  Counted as
// `lost` per input channel on SEXTANT_STATUS.
// A number at or below the previous one is a repeat or a restarted sender (counted from there on, no loss); a gap
// of more than `kMaxGap` is taken as a restart too (a sender that was away that long did not lose those messages
// on our account).  At most `max_senders` senders are followed; later ones are not (counted in `untracked`).
#include <cstdint>
#include <string>
#include <unordered_map>

namespace sextant::runtime {

class SequenceGaps {
 public:
  static constexpr int64_t kMaxGap = 1 << 20;

  explicit SequenceGaps(size_t max_senders = 1024) : max_senders_(max_senders) {}

  /// Messages missing right before `seq` of `sender` (0 for its first message, a repeat or a restart).
  int64_t observe(const std::string& sender, int64_t seq) {
    if (seq < 0) return 0;  // not a sequence number sextant's senders write
    auto it = last_.find(sender);
    if (it == last_.end()) {
      if (last_.size() >= max_senders_) {
        ++untracked_;
        return 0;
      }
      last_.emplace(sender, seq);
      return 0;
    }
    const int64_t prev = it->second;
    it->second = seq;
    if (seq <= prev || seq - prev > kMaxGap) return 0;  // (seq > prev: no overflow in the difference)
    return seq - prev - 1;
  }

  int64_t untracked() const { return untracked_; }
  size_t senders() const { return last_.size(); }

 private:
  size_t max_senders_;
  std::unordered_map<std::string, int64_t> last_;
  int64_t untracked_ = 0;
};

}  // namespace sextant::runtime
