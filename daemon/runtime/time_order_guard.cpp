#include "daemon/runtime/time_order_guard.hpp"

#include <algorithm>
#include <cstdio>

namespace sextant::runtime {
namespace {

using SteadyDuration = TimeOrderGuard::SteadyTime::duration;

constexpr size_t kRecentSignatures = 16;

std::string seconds(int64_t us) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", static_cast<double>(us) * 1e-6);
  return b;
}

uint64_t mix(int64_t utime, uint64_t signature) {
  // splitmix64 of the stamp, combined with the caller's signature.
  uint64_t z = static_cast<uint64_t>(utime) + 0x9e3779b97f4a7c15ULL + signature * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

SteadyDuration seconds_of(double s) {
  return std::chrono::duration_cast<SteadyDuration>(std::chrono::duration<double>(s));
}

}  // namespace

void TimeOrderGuard::forget(std::unordered_map<std::string, Stream>::iterator it) {
  expired_names_.push_back(it->first);
  streams_.erase(it);
  ++expired_;
}

void TimeOrderGuard::trim_expired() {
  const size_t bound = 2 * static_cast<size_t>(std::max(options_.max_streams, 1));
  if (expired_names_.size() <= bound) return;
  const size_t untold = expired_names_.size() - bound;
  expired_names_.erase(expired_names_.begin(), expired_names_.begin() + static_cast<std::ptrdiff_t>(untold));
  expired_untold_ += static_cast<int64_t>(untold);
}

void TimeOrderGuard::expire(SteadyTime now) {
  if (options_.idle_s <= 0) return;
  const auto idle = seconds_of(options_.idle_s);
  for (auto it = streams_.begin(); it != streams_.end();) {
    auto next = std::next(it);
    if (now - it->second.seen > idle) forget(it);
    it = next;
  }
  last_expiry_ = now;
  trim_expired();
}

bool TimeOrderGuard::evict(SteadyTime now) {
  if (options_.evict_idle_s <= 0 || now < no_eviction_before_) return false;
  const auto idle = seconds_of(options_.evict_idle_s);
  auto victim = streams_.end();
  SteadyTime oldest = SteadyTime::max();
  for (auto it = streams_.begin(); it != streams_.end(); ++it) {
    const Stream& s = it->second;
    oldest = std::min(oldest, s.seen);
    if (now - s.seen < idle) continue;
    if (victim == streams_.end() || s.messages < victim->second.messages ||
        (s.messages == victim->second.messages && s.seen < victim->second.seen))
      victim = it;
  }
  if (victim == streams_.end()) {
    no_eviction_before_ = oldest + idle;  // nobody can go before the longest-silent stream has been silent long enough
    return false;
  }
  forget(victim);
  trim_expired();
  ++evicted_;
  return true;
}

std::optional<TimeOrderGuard::Refusal> TimeOrderGuard::check(const std::string& stream, int64_t utime, bool strict,
                                                             uint64_t signature, std::optional<LiveClock> live,
                                                             SteadyTime replay_now) {
  const SteadyTime now = live ? live->now : replay_now;
  const auto max_ahead = static_cast<int64_t>(options_.max_ahead_s * 1e6);
  if (live && utime > live->wall_utime &&
      utime - live->wall_utime > static_cast<int64_t>(options_.max_ahead_of_wall_s * 1e6))
    return Refusal{"time_future", "utime " + std::to_string(utime) + " is " + seconds(utime - live->wall_utime) +
                                      " s ahead of the wall clock for " + stream};
  // Idle streams are looked for at most once a second, and when the table is full.
  if (options_.idle_s > 0 && now - last_expiry_ > std::chrono::seconds(1)) expire(now);
  auto it = streams_.find(stream);
  if (it == streams_.end()) {
    const auto full = [&] { return streams_.size() >= static_cast<size_t>(std::max(options_.max_streams, 0)); };
    if (full()) {
      expire(now);
      if (full() && live) evict(now);
      if (full())
        return Refusal{"too_many_sources", "a new source " + stream + " beyond the " +
                                               std::to_string(options_.max_streams) + " tracked (daemon.max_sources)"};
    }
    Stream s;
    s.clock = utime;
    s.recent.push_back(mix(utime, signature));
    s.seen = s.moved = now;
    s.messages = 1;
    streams_.emplace(stream, std::move(s));
    return std::nullopt;
  }
  Stream& s = it->second;
  s.seen = now;
  ++s.messages;
  const uint64_t sig = mix(utime, signature);
  if ((strict && utime == s.clock) || (!strict && std::find(s.recent.begin(), s.recent.end(), sig) != s.recent.end()))
    return Refusal{"time_order", "duplicate utime " + std::to_string(utime) + " for " + stream};
  // Live, the slack grows with the real time since the clock moved (a paused sender resumes later in data time too).
  const int64_t elapsed_us =
      live ? std::chrono::duration_cast<std::chrono::microseconds>(now - s.moved).count() : int64_t{0};
  const bool ahead = live && utime > s.clock && utime - s.clock > max_ahead + std::max<int64_t>(elapsed_us, 0);
  const bool behind = strict && utime < s.clock;
  if (!ahead && !behind) {
    s.jump.accepted();
    if (utime > s.clock) s.clock = utime, s.moved = now;
    s.recent.push_back(sig);
    if (s.recent.size() > kRecentSignatures) s.recent.pop_front();
    return std::nullopt;
  }
  // A possible jump: the last of a run of consistent refused messages re-synchronises the clock.
  if (s.jump.refused(utime, static_cast<uint64_t>(std::max<int64_t>(max_ahead, 0)), options_.resync_after)) {
    last_resync_ = stream + ": clock re-synchronised from " + std::to_string(s.clock) + " to " + std::to_string(utime) +
                   " after " + std::to_string(std::max(options_.resync_after, 1)) + " consistent messages";
    s.clock = utime;
    s.moved = now;
    s.recent.assign(1, sig);
    ++resyncs_;
    return std::nullopt;
  }
  if (ahead)
    return Refusal{"time_future", "utime " + std::to_string(utime) + " is " + seconds(utime - s.clock) +
                                      " s ahead of the previous " + std::to_string(s.clock) + " for " + stream};
  return Refusal{"time_order", "utime " + std::to_string(utime) + " before the previous " + std::to_string(s.clock) +
                                   " for " + stream};
}

}  // namespace sextant::runtime
