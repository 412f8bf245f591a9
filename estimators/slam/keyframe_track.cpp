#include "estimators/slam/keyframe_track.hpp"

#include "estimators/lie/pose_covariance.hpp"

#include <algorithm>
#include <iterator>

namespace sextant::slam {

void KeyframeTrack::extend_since_keyframe(const SE3& delta, const Matrix6d& q) {
  since_keyframe_ = compose_covariance(since_keyframe_, delta, q);
}

void KeyframeTrack::advance(int64_t utime, const SE3& pose, const Matrix6d& pose_covariance, size_t history) {
  last_utime_ = utime;
  last_odom_ = pose;
  if (odometry_.size() >= history)
    odometry_.erase(odometry_.begin(), odometry_.begin() + static_cast<std::ptrdiff_t>(odometry_.size() / 2));
  odometry_.emplace_back(utime, pose);
  last_odom_covariance_ = pose_covariance;
}

int64_t KeyframeTrack::add_keyframe(TrackKeyframe keyframe) {
  keyframe.id = std::max(keyframe.id, next_keyframe_id_);
  next_keyframe_id_ = keyframe.id + 1;
  since_keyframe_.setZero();
  by_utime_[keyframe.utime] = keyframes_.size();
  keyframes_.push_back(std::move(keyframe));
  return keyframes_.back().id;
}

void KeyframeTrack::replace_keyframes(std::vector<TrackKeyframe> keyframes,
                                      const std::vector<ThinnedKeyframe>& thinned) {
  keyframes_ = std::move(keyframes);
  by_utime_.clear();
  for (size_t i = 0; i < keyframes_.size(); ++i) by_utime_[keyframes_[i].utime] = i;
  // Records stay in time order: a thinning's are newer than the previous one's oldest survivors, so usually they
  // follow the records kept; a merge in place otherwise.
  const auto middle = static_cast<std::ptrdiff_t>(thinned_.size());
  thinned_.insert(thinned_.end(), thinned.begin(), thinned.end());
  const auto by_time = [](const ThinnedKeyframe& x, const ThinnedKeyframe& y) { return x.utime < y.utime; };
  if (!std::is_sorted(thinned.begin(), thinned.end(), by_time))
    std::sort(thinned_.begin() + middle, thinned_.end(), by_time);
  if (middle > 0 && middle < static_cast<std::ptrdiff_t>(thinned_.size()) &&
      by_time(thinned_[middle], thinned_[middle - 1]))
    std::inplace_merge(thinned_.begin(), thinned_.begin() + middle, thinned_.end(), by_time);
  // Counting every place's visits at every thinning would cost the whole record set each time: only once it has
  // grown by a quarter (so the cost per record stays constant).
  if (thinned_.size() > thinned_bounded_ + thinned_bounded_ / 4 + kThinnedRecordsPerPlace) forget_old_visits();
}

void KeyframeTrack::forget_old_visits() {
  std::map<KeyframePlace, size_t> visits;
  std::vector<char> keep(thinned_.size());
  for (size_t i = thinned_.size(); i-- > 0;) keep[i] = ++visits[thinned_[i].place] <= kThinnedRecordsPerPlace;
  size_t kept = 0;
  for (size_t i = 0; i < thinned_.size(); ++i)
    if (keep[i]) thinned_[kept++] = thinned_[i];
  thinned_.resize(kept);
  thinned_bounded_ = kept;
}

void KeyframeTrack::remap_variables(const std::vector<int>& remap) {
  for (auto& k : keyframes_) k.variable = remap[static_cast<size_t>(k.variable)];
}

std::optional<TrackPoint> KeyframeTrack::resolve(int64_t keyframe_id, int64_t utime, int64_t tolerance_us) const {
  // By id: a keyframe of the graph at exactly that time.
  const auto by_id = std::lower_bound(keyframes_.begin(), keyframes_.end(), keyframe_id,
                                      [](const TrackKeyframe& k, int64_t id) { return k.id < id; });
  if (keyframe_id >= 0 && by_id != keyframes_.end() && by_id->id == keyframe_id && by_id->utime == utime)
    return TrackPoint{static_cast<size_t>(by_id - keyframes_.begin()), SE3(), Matrix6d::Zero()};
  // The odometry pose at the time (exact stamp, as a front end answers about frames it was given).
  std::optional<SE3> at_time;
  auto at = std::lower_bound(odometry_.begin(), odometry_.end(), utime,
                             [](const std::pair<int64_t, SE3>& x, int64_t t) { return x.first < t; });
  if (at != odometry_.end() && at->first == utime) at_time = at->second;
  const auto thinned = std::lower_bound(thinned_.begin(), thinned_.end(), utime,
                                        [](const ThinnedKeyframe& k, int64_t t) { return k.utime < t; });
  if (!at_time && thinned != thinned_.end() && thinned->utime == utime) at_time = thinned->odom;
  // The nearest keyframe of the graph in time, within the tolerance: the odometry bridges the gap.
  auto hi = by_utime_.lower_bound(utime);
  std::optional<size_t> best;
  int64_t best_gap = tolerance_us + 1;
  if (hi != by_utime_.end() && hi->first - utime < best_gap) best = hi->second, best_gap = hi->first - utime;
  if (hi != by_utime_.begin()) {
    auto lo = std::prev(hi);
    if (utime - lo->first < best_gap) best = lo->second;
  }
  if (best) {
    const TrackKeyframe& kf = keyframes_[*best];
    if (kf.utime == utime) return TrackPoint{*best, SE3(), Matrix6d::Zero()};
    if (!at_time) return std::nullopt;
    return TrackPoint{*best, kf.odom.between(*at_time), Matrix6d::Zero()};
  }
  // A time whose keyframes were thinned: the keyframe of the graph before it on the odometry chain, the odometry from
  // there, and the covariance of the whole (composed) edge from that keyframe to the next one of the graph.
  if (!at_time || by_utime_.empty() || utime < by_utime_.begin()->first || utime > keyframes_.back().utime)
    return std::nullopt;
  const size_t k = std::prev(by_utime_.upper_bound(utime))->second;
  if (k + 1 >= keyframes_.size()) return std::nullopt;
  return TrackPoint{k, keyframes_[k].odom.between(*at_time), keyframes_[k + 1].edge_covariance};
}

std::optional<size_t> KeyframeTrack::position_of(int64_t id) const {
  const auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), id,
                                   [](const TrackKeyframe& k, int64_t x) { return k.id < x; });
  if (it == keyframes_.end() || it->id != id) return std::nullopt;
  return static_cast<size_t>(it - keyframes_.begin());
}

std::optional<size_t> KeyframeTrack::keyframe_at_or_before(int64_t utime) const {
  const auto after = by_utime_.upper_bound(utime);
  if (after == by_utime_.begin()) return std::nullopt;
  return std::prev(after)->second;
}

std::optional<TrackPoint> KeyframeTrack::anchor_at(int64_t utime) const {
  const std::optional<size_t> k = keyframe_at_or_before(utime);
  if (!k) return std::nullopt;
  SE3 pose = last_odom_;
  if (utime != last_utime_) {
    auto at = std::lower_bound(odometry_.begin(), odometry_.end(), utime,
                               [](const std::pair<int64_t, SE3>& x, int64_t t) { return x.first < t; });
    if (at == odometry_.end() || (at->first != utime && at == odometry_.begin())) return std::nullopt;
    if (at->first == utime) {
      pose = at->second;
    } else {
      const auto& [t0, p0] = *std::prev(at);
      const double a = static_cast<double>(utime - t0) / static_cast<double>(at->first - t0);
      pose = p0 * SE3::exp(a * p0.between(at->second).log());
    }
  }
  const Matrix6d cov = *k + 1 < keyframes_.size() ? keyframes_[*k + 1].edge_covariance : since_keyframe_;
  return TrackPoint{*k, keyframes_[*k].odom.between(pose), cov};
}

std::pair<SE3, Matrix6d> KeyframeTrack::odometry_path(size_t from, size_t to) const {
  const size_t lo = std::min(from, to), hi = std::max(from, to);
  Matrix6d path = Matrix6d::Zero();
  SE3 chain;
  for (size_t k = lo + 1; k <= hi; ++k) {
    path = compose_covariance(path, keyframes_[k].edge, keyframes_[k].edge_covariance);
    chain = chain * keyframes_[k].edge;
  }
  if (from > to) {  // the covariance of the inverse motion: Ad(X) P Ad(X)'
    const Matrix6d ad = chain.adjoint();
    path = ad * path * ad.transpose();
    chain = chain.inverse();
  }
  return {chain, path};
}

void KeyframeTrack::save(archive::ArchiveWriter& w) const {
  w(last_utime_)(last_odom_)(last_odom_covariance_)(since_keyframe_);
  w(static_cast<uint64_t>(keyframes_.size()));
  for (const TrackKeyframe& k : keyframes_)
    w(k.id)(k.utime)(k.variable)(k.odom)(k.odom_covariance)(k.edge_covariance)(k.edge);
  w(static_cast<uint64_t>(thinned_.size()));
  for (const ThinnedKeyframe& k : thinned_) w(k.id)(k.utime)(k.odom)(k.place[0])(k.place[1])(k.place[2])(k.place[3]);
  w(next_keyframe_id_)(odometry_);
}

void KeyframeTrack::load(archive::ArchiveReader& r) {
  r(last_utime_)(last_odom_)(last_odom_covariance_)(since_keyframe_);
  keyframes_.clear();
  by_utime_.clear();
  const uint64_t keyframes = r.count(1, "the keyframes");
  for (uint64_t k = 0; k < keyframes; ++k) {
    TrackKeyframe node;
    r(node.id)(node.utime)(node.variable)(node.odom)(node.odom_covariance)(node.edge_covariance)(node.edge);
    by_utime_[node.utime] = keyframes_.size();
    keyframes_.push_back(std::move(node));
  }
  thinned_.clear();
  const uint64_t thinned = r.count(1, "the thinned keyframes");
  for (uint64_t k = 0; k < thinned; ++k) {
    ThinnedKeyframe t;
    r(t.id)(t.utime)(t.odom)(t.place[0])(t.place[1])(t.place[2])(t.place[3]);
    thinned_.push_back(t);
  }
  thinned_bounded_ = thinned_.size();
  r(next_keyframe_id_)(odometry_);
}

}  // namespace sextant::slam
