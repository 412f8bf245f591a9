#include "daemon/runtime/publisher.hpp"

#include "daemon/runtime/codec.hpp"

#include <algorithm>
#include <cctype>

namespace sextant::runtime {

Publisher::Publisher(config::Channels channels, std::string sender, std::string primary_estimator, RawSink raw,
                     size_t max_tracked)
    : channels_(std::move(channels)),
      sender_(std::move(sender)),
      primary_(std::move(primary_estimator)),
      raw_(std::move(raw)),
      max_tracked_(std::max<size_t>(max_tracked, 1)) {}

std::string Publisher::fused_pose_channel(const std::string& estimator) const {
  if (estimator == primary_) return channels_.full(channels_.fused_pose);
  std::string upper = estimator;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return std::toupper(c); });
  return channels_.full(channels_.fused_pose + "_" + upper);
}

template <class Msg>
void Publisher::send(const std::string& channel, Msg msg) {
  // Called with mutex_ held: sequence numbers and the order on the wire agree.
  msg.sender = sender_;
  msg.seq = seq_[channel]++;
  std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes_[channel] += static_cast<int64_t>(bytes.size());
  raw_(channel, bytes, msg.utime);
}

bool Publisher::publish(const engine::Output& output) {
  std::lock_guard lock(mutex_);
  return std::visit(
      [&](const auto& o) {
        using T = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<T, engine::FusedPose>) {
          const std::string channel = fused_pose_channel(o.estimator);
          const std::string key = channel + "/" + o.source;
          if (last_fused_utime_.size() >= max_tracked_ && !last_fused_utime_.contains(key)) {
            // Only when the stages did not forget their bodies (they are bounded by daemon.max_sources): the entry
            // published longest ago goes, a linear search at most once per new name.
            last_fused_utime_.erase(std::min_element(last_fused_utime_.begin(), last_fused_utime_.end(),
                                                     [](const auto& a, const auto& b) { return a.second < b.second; }));
            ++evicted_;
          }
          auto [it, inserted] = last_fused_utime_.try_emplace(key, o.utime);
          if (!inserted) {
            if (o.utime <= it->second) {
              ++not_monotonic_;
              return false;
            }
            it->second = o.utime;
          }
          sextant::fused_pose_t m = to_message(o, sender_, 0);
          if (wall_) {  // sextantd: the lag goes out with the pose (replay has no wall clock: 0)
            m.lag_us = wall_() - o.utime;
            lag_.last_us = m.lag_us;
            lag_.max_us = std::max(lag_.max_us, lag_.last_us);
            lag_min_ = std::min(lag_min_.value_or(lag_.last_us), lag_.last_us);
          }
          send(channel, std::move(m));
        } else if constexpr (std::is_same_v<T, engine::GeoPose>) {
          send(channels_.full(channels_.fused_geo), to_message(o, sender_, 0));
        } else if constexpr (std::is_same_v<T, engine::Trajectory>) {
          send(channels_.full(channels_.trajectory), to_message(o, sender_, 0));
        } else if constexpr (std::is_same_v<T, engine::MatchRequest>) {
          send(channels_.full(channels_.match_requests), to_message(o, sender_, 0));
        } else if constexpr (std::is_same_v<T, engine::Targets>) {
          send(channels_.full(channels_.targets), to_message(o, sender_, 0));
        } else if constexpr (std::is_same_v<T, engine::LandmarkMap>) {
          send(channels_.full(channels_.landmark_map), to_message(o, sender_, 0));
        } else if constexpr (std::is_same_v<T, engine::FleetContributions>) {
          send(channels_.fleet, to_message(o, sender_, 0));  // the fleet's channels: no prefix
        } else if constexpr (std::is_same_v<T, engine::FleetControl>) {
          send(channels_.fleet_control, to_message(o, sender_, 0));
        }
        return true;
      },
      output);
}

void Publisher::measure_lag(std::function<int64_t()> wall_utime) {
  std::lock_guard lock(mutex_);
  wall_ = std::move(wall_utime);
}

Publisher::Lag Publisher::take_lag() {
  std::lock_guard lock(mutex_);
  const bool saw_pose = lag_min_.has_value();
  if (saw_pose) {
    lag_minima_.push_back(*lag_min_);
    if (lag_minima_.size() > kUsualLagReports) lag_minima_.pop_front();
    lag_min_.reset();
  }
  Lag out = lag_;
  out.usual_us = lag_minima_.empty() ? 0 : *std::min_element(lag_minima_.begin(), lag_minima_.end());
  out.previous_us = lag_reported_.value_or(out.max_us);  // at the first report: nothing to compare with
  if (saw_pose) lag_reported_ = lag_.last_us;
  lag_.max_us = lag_.last_us;
  return out;
}

void Publisher::publish(const sextant::status_t& status) {
  std::lock_guard lock(mutex_);
  send(channels_.full(channels_.status), status);
}

std::map<std::string, int64_t> Publisher::counts() const {
  std::lock_guard lock(mutex_);
  return seq_;
}

std::map<std::string, int64_t> Publisher::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

int64_t Publisher::not_monotonic() const {
  std::lock_guard lock(mutex_);
  return not_monotonic_;
}

void Publisher::forget(const std::string& estimator, const std::string& source) {
  const std::string key = fused_pose_channel(estimator) + "/" + source;
  std::lock_guard lock(mutex_);
  forgotten_ += static_cast<int64_t>(last_fused_utime_.erase(key));
}

size_t Publisher::fused_pose_sources() const {
  std::lock_guard lock(mutex_);
  return last_fused_utime_.size();
}

int64_t Publisher::fused_pose_sources_forgotten() const {
  std::lock_guard lock(mutex_);
  return forgotten_;
}

int64_t Publisher::fused_pose_sources_evicted() const {
  std::lock_guard lock(mutex_);
  return evicted_;
}

}  // namespace sextant::runtime
