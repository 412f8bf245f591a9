#pragma once
// An LCM log's records in the order of their messages' own time stamps, as a replay feeds them to the engine.
//
// A recorder writes events in the order they arrived; a replay goes by the time each message carries (every sextant
// type starts with `int64_t utime`), so that a log merged from several recorders, or one whose senders' packets
// crossed on the network, replays as the senders stamped it.  Two passes over the file: the first sorts (16 bytes a
// record while sorting, 4 bytes a record kept); the second reads in file order and holds a record read before its
// turn in memory, up to a budget of bytes.  Past the budget it keeps only where such a record starts and reads it
// again when its turn comes: one message stamped long before the rest (a sender whose clock said 1970, late in a
// two-hour log) costs a second read of what it jumped ahead of, never the whole log in memory.
#include "daemon/runtime/lcm_log.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace sextant::tools {

/// The utime a message carries after its 8-byte fingerprint, or nullopt for a message too short to carry one.
std::optional<int64_t> peek_utime(const std::vector<uint8_t>& data);
/// The stamp a replay orders and paces a record by: its message's utime, or the log's stamp for a message without one.
inline int64_t replay_stamp(const runtime::LogRecord& r) { return peek_utime(r.data).value_or(r.timestamp); }

class TimeOrderedLog {
 public:
  /// Bytes of records held in memory while they wait for their turn, by default.
  static constexpr size_t kHeldBytes = size_t{64} << 20;

  /// Pass 1: reads `path` and sorts its good records by replay_stamp, ties
  /// in file order.  Throws std::runtime_error naming the path when it cannot be read.
  explicit TimeOrderedLog(std::string path, size_t held_bytes = kHeldBytes);

  size_t records() const { return rank_.size(); }
  /// What pass 1 found damaged (skipped events and bytes); pass 2 skips the same.
  const runtime::LogDamage& damage() const { return damage_; }

  /// Pass 2: `step` on every record in its turn.  A record that vanished from the file since pass 1 (the file was cut
  /// short under us) ends the pass early; one that grew is read up to what pass 1 saw.
  void for_each(const std::function<void(const runtime::LogRecord&)>& step);

  /// Records of the last pass read twice because the held bytes were over budget when they were first read.
  int64_t read_again() const { return read_again_; }
  /// The most bytes of records held in memory at once in the last pass.
  size_t held_bytes_peak() const { return held_peak_; }

 private:
  std::string path_;
  size_t budget_;
  std::vector<uint32_t> rank_;  // rank_[i]: the turn of the file's i-th good record
  runtime::LogDamage damage_;
  int64_t read_again_ = 0;
  size_t held_peak_ = 0;
};

}  // namespace sextant::tools
