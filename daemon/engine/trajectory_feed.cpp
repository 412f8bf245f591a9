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

// What changed since the last publication: ids gone (removed), keyframes new (fresh) and moved, the latter with
// how far past the thresholds (indices into the current keyframes).
struct TrajectoryFeed::Changes {
  std::vector<int64_t> removed;
  std::vector<size_t> fresh;
  std::vector<std::pair<double, size_t>> moved;
};

std::vector<Trajectory> TrajectoryFeed::publish(int64_t utime, const std::vector<Keyframe>& current,
                                                const Trajectory& header, bool flush) {
  started_ = true;
  if (options_.rate_hz > 0) next_utime_ = utime + static_cast<int64_t>(std::llround(1e6 / options_.rate_hz));
  const Changes changes = compare_with_published(current, flush);
  const std::vector<size_t> send = choose_keyframes_to_send(changes, flush);
  // Every message starts as the header, at `utime`, with the current number of keyframes.
  Trajectory first = header;
  first.utime = utime;
  first.total_keyframes = static_cast<int>(current.size());
  first.keyframes.clear();
  first.removed_ids.clear();
  std::vector<Trajectory> out;
  add_updates(out, first, current, send, changes.removed);
  if (!flush && options_.snapshot_chunk > 0 && !current.empty()) add_snapshot_chunk(out, first, current);
  return out;
}

// One merge pass over the published and the current keyframes (both by id); ids gone leave `published_`.  When
// flushing, any change of pose counts as a move.
TrajectoryFeed::Changes TrajectoryFeed::compare_with_published(const std::vector<Keyframe>& current, bool flush) {
  Changes c;
  auto pub = published_.begin();
  for (size_t k = 0; k < current.size(); ++k) {
    const Keyframe& kf = current[k];
    while (pub != published_.end() && pub->first < kf.id) c.removed.push_back(pub->first), pub = published_.erase(pub);
    if (pub == published_.end() || pub->first != kf.id) {
      c.fresh.push_back(k);
      continue;
    }
    const double dt = (pub->second.position - kf.pose.position).norm();
    const double dr = rotation_between(pub->second, kf.pose);
    const double score = std::max(dt / options_.move_translation, dr / options_.move_rotation);
    if (flush ? (pub->second.position != kf.pose.position ||
                 pub->second.orientation.coeffs() != kf.pose.orientation.coeffs())
              : score > 1.0)
      c.moved.emplace_back(score, k);
    ++pub;
  }
  while (pub != published_.end()) c.removed.push_back(pub->first), pub = published_.erase(pub);
  return c;
}

// The new keyframes, then the moved ones farthest past the thresholds first, up to the tick's budget (none when
// flushing); in id order.
std::vector<size_t> TrajectoryFeed::choose_keyframes_to_send(const Changes& changes, bool flush) const {
  std::vector<std::pair<double, size_t>> moved = changes.moved;
  std::sort(moved.begin(), moved.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  std::vector<size_t> send = changes.fresh;
  const size_t budget =
      flush ? std::numeric_limits<size_t>::max() : static_cast<size_t>(std::max(0, options_.max_keyframes_per_tick));
  if (send.size() > budget) send.resize(budget);
  for (size_t i = 0; i < moved.size() && send.size() < budget; ++i) send.push_back(moved[i].second);
  std::sort(send.begin(), send.end());
  return send;
}

// UPDATE messages: keyframes and removed ids packed under the per-message byte budget.
void TrajectoryFeed::add_updates(std::vector<Trajectory>& out, const Trajectory& first,
                                 const std::vector<Keyframe>& current, const std::vector<size_t>& send,
                                 const std::vector<int64_t>& removed) {
  const int64_t message_bytes = std::max(1, options_.max_keyframes_per_message) * kKeyframeBytes;
  size_t next_kf = 0, next_removed = 0;
  while (next_kf < send.size() || next_removed < removed.size()) {
    out.push_back(first);
    Trajectory& t = out.back();
    t.kind = Trajectory::Kind::kUpdate;
    int64_t bytes = 0;
    for (; next_removed < removed.size() && bytes + kRemovedIdBytes <= message_bytes; bytes += kRemovedIdBytes)
      t.removed_ids.push_back(removed[next_removed++]);
    for (; next_kf < send.size() && bytes + kKeyframeBytes <= message_bytes; bytes += kKeyframeBytes) {
      const Keyframe& kf = current[send[next_kf++]];
      t.keyframes.push_back(kf);
      published_[kf.id] = kf.pose;
    }
  }
}

// One chunk of the rolling snapshot: the next keyframes from the cursor; the last chunk of a cycle says how many
// the cycle had and starts the next one.
void TrajectoryFeed::add_snapshot_chunk(std::vector<Trajectory>& out, const Trajectory& first,
                                        const std::vector<Keyframe>& current) {
  const size_t chunk =
      static_cast<size_t>(std::min(options_.snapshot_chunk, std::max(1, options_.max_keyframes_per_message)));
  if (snapshot_next_chunk_ == 0) {
    snapshot_cursor_ = std::numeric_limits<int64_t>::min();
    snapshot_chunks_ = static_cast<int>((current.size() + chunk - 1) / chunk);
  }
  const auto from = std::lower_bound(current.begin(), current.end(), snapshot_cursor_,
                                     [](const Keyframe& k, int64_t id) { return k.id < id; });
  const size_t begin = static_cast<size_t>(from - current.begin());
  const size_t end = std::min(current.size(), begin + chunk);
  out.push_back(first);
  Trajectory& t = out.back();
  t.kind = Trajectory::Kind::kSnapshot;
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

void TrajectoryFeed::save(archive::ArchiveWriter& w) const {
  w(started_)(next_utime_)(published_)(snapshot_cursor_)(snapshot_id_)(snapshot_next_chunk_)(snapshot_chunks_);
}

void TrajectoryFeed::load(archive::ArchiveReader& r) {
  r(started_)(next_utime_)(published_)(snapshot_cursor_)(snapshot_id_)(snapshot_next_chunk_)(snapshot_chunks_);
}

}  // namespace sextant::engine
