#include "daemon/runtime/intake.hpp"

namespace sextant::runtime {
namespace {

// The stream a message's time order is checked in, and whether it must strictly increase.
std::pair<std::string, bool> stream_of(const std::string& channel, const engine::Event& e) {
  return std::visit(
      [&](const auto& x) -> std::pair<std::string, bool> {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, engine::Odometry>) return {channel + "/" + x.source, true};
        else if constexpr (std::is_same_v<T, engine::BearingScan>)
          return {channel + "/sensor " + std::to_string(x.sensor_id), true};
        else if constexpr (std::is_same_v<T, engine::LandmarkSightings>) return {channel + "/" + x.source, false};
        else return {channel + "/" + x.source + "/" + std::to_string(x.utime_from) + "-" + std::to_string(x.utime_to), false};
      },
      e);
}

}  // namespace

Intake::Intake(ChannelStats& stats, RejectHook on_reject) : stats_(stats), on_reject_(std::move(on_reject)) {}

void Intake::add_channel(const std::string& channel, InputKind kind) {
  channels_[channel] = kind;
  stats_.add(channel);
}

void Intake::reject(const std::string& channel, const std::string& reason, const std::string& message) {
  stats_.rejected(channel, reason, message);
  if (on_reject_) on_reject_(channel, reason, message);
}

std::optional<engine::Event> Intake::accept(const std::string& channel, const void* data, size_t size) {
  auto it = channels_.find(channel);
  if (it == channels_.end()) return std::nullopt;
  stats_.received(channel);
  Decoded d = decode_event(it->second, data, size);
  if (auto* r = std::get_if<Rejection>(&d)) {
    reject(channel, r->reason, channel + ": " + r->message);
    return std::nullopt;
  }
  engine::Event event = std::get<engine::Event>(std::move(d));
  const auto [stream, strict] = stream_of(channel, event);
  if (auto why = order_.check(stream, engine::event_utime(event), strict)) {
    reject(channel, "time_order", channel + ": " + *why);
    return std::nullopt;
  }
  stats_.decoded(channel);
  return event;
}

}  // namespace sextant::runtime
