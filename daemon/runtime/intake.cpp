#include "daemon/runtime/intake.hpp"

#include <algorithm>
#include <chrono>

namespace sextant::runtime {
namespace {

struct StreamKey {
  std::string stream;      // whose clock the stamp is checked against
  bool strict = false;     // must strictly increase
  uint64_t signature = 0;  // tells apart messages of one stream that may share a stamp
};

StreamKey stream_of(const std::string& channel, const engine::Event& e) {
  return std::visit(
      [&](const auto& x) -> StreamKey {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, engine::Odometry>)
          return {channel + "/" + x.source, true, 0};
        else if constexpr (std::is_same_v<T, engine::BearingScan>)
          return {channel + "/sensor " + std::to_string(x.sensor_id), true, 0};
        else if constexpr (std::is_same_v<T, engine::LandmarkSightings>)
          return {channel + "/" + x.source, false, 0};
        else if constexpr (std::is_same_v<T, engine::ImuSample> || std::is_same_v<T, engine::GnssFix>)
          return {channel + "/" + x.source + "/" + x.frame, true, 0};  // one clock per sensor of a body
        else if constexpr (std::is_same_v<T, engine::FleetContributions> || std::is_same_v<T, engine::FleetControl>)
          return {channel + "/" + x.sender, false, 0};  // not time-checked: the exchange orders them (accept_unguarded)
        else
          return {channel + "/" + x.source, false,
                  static_cast<uint64_t>(x.utime_from) * 0x9e3779b97f4a7c15ULL ^ static_cast<uint64_t>(x.utime_to)};
      },
      e);
}

}  // namespace

Arrival Arrival::now() {
  return {std::chrono::steady_clock::now(),
          std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
              .count()};
}

Arrival Arrival::at_log_time(int64_t utime) {
  // The steady clock counts nanoseconds: a stamp beyond +-2^62 ns (about 146 years) of its epoch, as only a damaged
  // or hostile message carries, saturates there instead of overflowing, and the headroom keeps the guard's
  // differences and sums with idle times representable.
  using std::chrono::nanoseconds;
  constexpr int64_t kLimitUs = (int64_t{1} << 62) / 1000;
  const int64_t us = std::clamp(utime, -kLimitUs, kLimitUs);
  return {std::chrono::steady_clock::time_point(std::chrono::duration_cast<nanoseconds>(std::chrono::microseconds(us))),
          utime};
}

IntakeOptions intake_options(const config::DaemonConfig& c, bool live) {
  IntakeOptions o;
  o.live = live;
  o.time = TimeGuardOptions{c.max_ahead_s, c.time_resync_messages, c.max_ahead_of_wall_s,
                            c.max_sources, c.source_idle_s,        c.source_evict_idle_s};
  o.plausibility = c.plausibility;
  o.source_handover_s = c.source_handover_s;
  return o;
}

Intake::Intake(ChannelStats& stats, RejectHook on_reject, IntakeOptions options)
    : stats_(stats),
      on_reject_(std::move(on_reject)),
      options_(options),
      order_(options.time),
      plausible_(options.plausibility, options.time.resync_after,
                 static_cast<size_t>(std::max(options.time.max_streams, 1))),
      claims_(options.source_handover_s, static_cast<size_t>(std::max(options.time.max_streams, 1)) * 4) {}

void Intake::add_channel(const std::string& channel, InputKind kind) {
  channels_[channel] = kind;
  sequences_.try_emplace(channel, static_cast<size_t>(std::max(options_.time.max_streams, 0)) * 4);
  stats_.add(channel);
}

void Intake::reject(const std::string& channel, const std::string& reason, const std::string& message) {
  stats_.rejected(channel, reason, message);
  if (on_reject_) on_reject_(channel, reason, message);
}

std::optional<engine::Event> Intake::accept(const std::string& channel, const void* data, size_t size,
                                            Arrival arrival) {
  auto it = channels_.find(channel);
  if (it == channels_.end()) return std::nullopt;
  stats_.received(channel);
  resynced_body_.clear();
  try {
    return accept_unguarded(channel, it->second, data, size, arrival);
  } catch (const std::exception& e) {
    reject(channel, "internal", channel + ": " + e.what());
    return std::nullopt;
  }
}

std::optional<engine::Event> Intake::accept_unguarded(const std::string& channel, InputKind kind, const void* data,
                                                      size_t size, Arrival arrival) {
  MessageOrigin origin{{}, -1};
  Decoded d = decode_event(kind, data, size, &origin);
  // When the message decoded, its sender's sequence number tells what was lost before it (even if it is invalid).
  if (origin.seq >= 0)
    if (const int64_t lost = sequences_.at(channel).observe(origin.sender, origin.seq); lost > 0)
      stats_.lost(channel, origin.sender, lost);
  if (auto* r = std::get_if<Rejection>(&d)) {
    reject(channel, r->reason, channel + ": " + r->message);
    return std::nullopt;
  }
  engine::Event event = std::get<engine::Event>(std::move(d));
  // A fleet member's message is not a sensor's: no clock, body or physics to check here; the graph stage's exchange
  // (daemon/engine/fleet_exchange.hpp) orders it by its stream's numbers and decides whom to hear.
  if (kind == InputKind::kFleet || kind == InputKind::kFleetControl) {
    stats_.decoded(channel);
    return event;
  }
  const StreamKey key = stream_of(channel, event);
  if (!claims_.claim(key.stream, origin.sender, engine::event_utime(event))) {
    reject(
        channel, "source_claimed",
        channel + ": '" + engine::event_source(event) + "' is held by another sender; '" + origin.sender + "' refused");
    return std::nullopt;
  }
  std::optional<TimeOrderGuard::LiveClock> live;
  if (options_.live) live = TimeOrderGuard::LiveClock{arrival.wall_utime, arrival.steady};
  const int64_t resyncs = order_.resyncs();
  if (auto why =
          order_.check(key.stream, engine::event_utime(event), key.strict, key.signature, live, arrival.steady)) {
    reject(channel, why->reason, channel + ": " + why->message);
    return std::nullopt;
  }
  // A stream whose clock was re-synchronised starts afresh: its motion before the jump says nothing about after.
  if (order_.resyncs() != resyncs) plausible_.forget(key.stream);
  if (auto why = plausible_.check(key.stream, event)) {
    reject(channel, why->reason, channel + ": " + why->message);
    return std::nullopt;
  }
  if (order_.resyncs() != resyncs || plausible_.resynced())
    if (const auto* o = std::get_if<engine::Odometry>(&event)) resynced_body_ = o->source;
  stats_.decoded(channel);
  return event;
}

std::vector<std::string> Intake::take_expired_bodies() {
  std::vector<std::string> bodies;
  for (const std::string& stream : order_.take_expired()) {
    plausible_.forget(stream);
    claims_.forget(stream);
    for (const auto& [channel, kind] : channels_)
      if (kind == InputKind::kOdometry && stream.size() > channel.size() &&
          stream.compare(0, channel.size(), channel) == 0 && stream[channel.size()] == '/')
        bodies.push_back(stream.substr(channel.size() + 1));
  }
  return bodies;
}

}  // namespace sextant::runtime
