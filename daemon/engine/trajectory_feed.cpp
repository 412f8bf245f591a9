#include "daemon/engine/trajectory_feed.hpp"

#include "daemon/engine/event_archive.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sextant::engine {
namespace {

// Bytes of one keyframe_t and of one removed id on the wire: the budget of a message is counted in these.
constexpr int64_t kKeyframeBytes = 72, kRemovedIdBytes = 8;

double rotation_between(const Pose& a, const Pose& b) { return a.orientation.angularDistance(b.orientation); }

}  // namespace

std::vector<Trajectory> TrajectoryFeed::publish(int64_t utime, const std::vector<Keyframe>& current,
                                                const Trajectory& header, bool flush) {
  started_ = true;
  if (options_.rate_hz > 0) next_utime_ = utime + static_cast<int64_t>(std::llround(1e6 / options_.rate_hz));

  // One merge pass over the published and the current keyframes (both by id).
  std::vector<int64_t> removed;
  std::vector<size_t> fresh;                       // indices into `current`
  std::vector<std::pair<double, size_t>> moved;    // (how far past the thresholds, index)
  auto pub = published_.begin();
  for (size_t k = 0; k < current.size(); ++k) {
    const Keyframe& kf = current[k];
    while (pub != published_.end() && pub->first < kf.id) removed.push_back(pub->first), pub = published_.erase(pub);
    if (pub == published_.end() || pub->first != kf.id) {
      fresh.push_back(k);
      continue;
    }
    const double dt = (pub->second.position - kf.pose.position).norm();
    const double dr = rotation_between(pub->second, kf.pose);
    const double score = std::max(dt / options_.move_translation, dr / options_.move_rotation);
    if (flush ? (pub->second.position != kf.pose.position || pub->second.orientation.coeffs() != kf.pose.orientation.coeffs())
              : score > 1.0)
      moved.emplace_back(score, k);
    ++pub;
  }
  while (pub != published_.end()) removed.push_back(pub->first), pub = published_.erase(pub);

  std::sort(moved.begin(), moved.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  std::vector<size_t> send = fresh;
  const size_t budget = flush ? std::numeric_limits<size_t>::max() : static_cast<size_t>(std::max(0, options_.max_keyframes_per_tick));
  if (send.size() > budget) send.resize(budget);
  for (size_t i = 0; i < moved.size() && send.size() < budget; ++i) send.push_back(moved[i].second);
  std::sort(send.begin(), send.end());

  std::vector<Trajectory> out;
  auto start_message = [&](Trajectory::Kind kind) -> Trajectory& {
    Trajectory t = header;
    t.utime = utime;
    t.kind = kind;
    t.total_keyframes = static_cast<int>(current.size());
    t.keyframes.clear();
    t.removed_ids.clear();
    out.push_back(std::move(t));
    return out.back();
  };
  // UPDATE messages: keyframes and removed ids packed under the per-message byte budget.
  const int64_t message_bytes = std::max(1, options_.max_keyframes_per_message) * kKeyframeBytes;
  size_t next_kf = 0, next_removed = 0;
  while (next_kf < send.size() || next_removed < removed.size()) {
    Trajectory& t = start_message(Trajectory::Kind::kUpdate);
    int64_t bytes = 0;
    for (; next_removed < removed.size() && bytes + kRemovedIdBytes <= message_bytes; bytes += kRemovedIdBytes)
      t.removed_ids.push_back(removed[next_removed++]);
    for (; next_kf < send.size() && bytes + kKeyframeBytes <= message_bytes; bytes += kKeyframeBytes) {
      const Keyframe& kf = current[send[next_kf++]];
      t.keyframes.push_back(kf);
      published_[kf.id] = kf.pose;
    }
  }

  // One chunk of the rolling snapshot.
  if (!flush && options_.snapshot_chunk > 0 && !current.empty()) {
    const size_t chunk = static_cast<size_t>(std::min(options_.snapshot_chunk, std::max(1, options_.max_keyframes_per_message)));
    if (snapshot_next_chunk_ == 0) {
      snapshot_cursor_ = std::numeric_limits<int64_t>::min();
      snapshot_chunks_ = static_cast<int>((current.size() + chunk - 1) / chunk);
    }
    const auto first = std::lower_bound(current.begin(), current.end(), snapshot_cursor_,
                                        [](const Keyframe& k, int64_t id) { return k.id < id; });
    const size_t begin = static_cast<size_t>(first - current.begin());
    const size_t end = std::min(current.size(), begin + chunk);
    Trajectory& t = start_message(Trajectory::Kind::kSnapshot);
    t.snapshot_id = snapshot_id_;
    t.chunk = snapshot_next_chunk_;
    t.num_chunks = std::max(snapshot_chunks_, snapshot_next_chunk_ + 1);
    t.range_first = snapshot_cursor_;
    const bool last = end == current.size();
    t.range_last = last ? std::numeric_limits<int64_t>::max() : current[end - 1].id;
    for (size_t k = begin; k < end; ++k) {
      t.keyframes.push_back(current[k]);
      published_[current[k].id] = current[k].pose;
    }
    if (last) {
      t.num_chunks = snapshot_next_chunk_ + 1;
      snapshot_next_chunk_ = 0;
      ++snapshot_id_;
    } else {
      snapshot_cursor_ = current[end - 1].id + 1;
      ++snapshot_next_chunk_;
    }
  }
  return out;
}

void TrajectoryFeed::save(archive::ArchiveWriter& w) const {
  w(started_)(next_utime_)(published_)(snapshot_cursor_)(snapshot_id_)(snapshot_next_chunk_)(snapshot_chunks_);
}

void TrajectoryFeed::load(archive::ArchiveReader& r) {
  r(started_)(next_utime_)(published_)(snapshot_cursor_)(snapshot_id_)(snapshot_next_chunk_)(snapshot_chunks_);
}

}  // namespace sextant::engine
