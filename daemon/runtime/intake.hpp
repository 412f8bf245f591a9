#pragma once
// The input side shared by sextantd and `sextant replay`: raw bytes on a known channel -> a validated event, or a
// counted rejection.  One instance per input stream; not thread-safe (the daemon calls it from its LCM thread,
// replay from its loop).
#include "daemon/runtime/channel_stats.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/time_order_guard.hpp"

#include <functional>
#include <map>
#include <optional>
#include <string>

namespace sextant::runtime {

class Intake {
 public:
  /// `on_reject(channel, reason, message)` is told about every rejection (for rate-limited logging).
  using RejectHook = std::function<void(const std::string&, const std::string&, const std::string&)>;

  explicit Intake(ChannelStats& stats, RejectHook on_reject = {});

  void add_channel(const std::string& channel, InputKind kind);
  const std::map<std::string, InputKind>& channels() const { return channels_; }

  /// Decodes, validates and time-checks one message; nullopt when it was rejected (and counted).
  std::optional<engine::Event> accept(const std::string& channel, const void* data, size_t size);

 private:
  void reject(const std::string& channel, const std::string& reason, const std::string& message);

  ChannelStats& stats_;
  RejectHook on_reject_;
  std::map<std::string, InputKind> channels_;
  TimeOrderGuard order_;
};

}  // namespace sextant::runtime
