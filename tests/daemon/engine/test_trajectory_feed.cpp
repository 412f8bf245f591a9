// TrajectoryFeed: a subscriber applying the rebuild rule of trajectory_t.lcm holds the current trajectory; updates
// carry only new and moved keyframes within the budget, the rest follows; removed keyframes are announced; the rolling
// snapshot repairs a subscriber that missed messages; every message stays under the byte budget.  The subscriber is
// TrajectoryRebuild, checked against the feed's input.
#include "daemon/engine/trajectory_feed.hpp"
#include "daemon/engine/trajectory_rebuild.hpp"

#include <doctest/doctest.h>

#include <map>
#include <random>

using namespace sextant::engine;

namespace {

// The subscriber's side (TrajectoryRebuild), and how far what it holds is from the truth.
struct Subscriber {
  TrajectoryRebuild rebuild;
  void apply(const Trajectory& t) { rebuild.add(t); }
  size_t size() const { return rebuild.keyframes().size(); }
  // The largest distance between what is held and `truth` (1e9 when the id sets differ).
  double worst(const std::vector<Keyframe>& truth) const {
    const auto& held = rebuild.keyframes();
    if (held.size() != truth.size()) return 1e9;
    double w = 0;
    for (const auto& k : truth) {
      auto it = held.find(k.id);
      if (it == held.end()) return 1e9;
      w = std::max(w, (it->second.pose.position - k.pose.position).norm());
    }
    return w;
  }
};

Keyframe keyframe(int64_t id, double x, double y) {
  Keyframe k;
  k.id = id;
  k.utime = 1'000'000 * id;
  k.pose.position = Eigen::Vector3d(x, y, 0);
  return k;
}

}  // namespace

TEST_CASE("trajectory feed: rate, budget, moved keyframes, removals and the final flush") {
  TrajectoryFeedOptions o;
  o.rate_hz = 1.0;
  o.max_keyframes_per_tick = 50;
  o.max_keyframes_per_message = 20;
  o.snapshot_chunk = 0;  // updates alone
  TrajectoryFeed feed(o);
  Subscriber sub;
  std::vector<Keyframe> current;
  for (int i = 0; i < 120; ++i) current.push_back(keyframe(i, i, 0));

  CHECK(feed.due(0));
  auto msgs = feed.publish(0, current, Trajectory{});
  CHECK(!feed.due(999'999));
  CHECK(feed.due(1'000'000));
  size_t sent = 0;
  for (const auto& m : msgs) {
    CHECK(m.kind == Trajectory::Kind::kUpdate);
    CHECK(m.keyframes.size() <= 20);
    CHECK(m.total_keyframes == 120);
    sent += m.keyframes.size();
    sub.apply(m);
  }
  CHECK(sent == 50);  // the budget: the rest waits
  for (int64_t t = 1; t <= 2; ++t)
    for (const auto& m : feed.publish(t * 1'000'000, current, Trajectory{})) sub.apply(m);
  CHECK(sub.worst(current) == 0.0);
  // Nothing changed: nothing is sent.
  CHECK(feed.publish(3'000'000, current, Trajectory{}).empty());

  // A loop closure bends the second half: only the keyframes that moved past 1 cm are sent, largest moves first.
  for (int i = 60; i < 120; ++i) current[static_cast<size_t>(i)].pose.position.y() = (i - 60) * 0.001;  // 0 .. 5.9 cm
  msgs = feed.publish(4'000'000, current, Trajectory{});
  sent = 0;
  for (const auto& m : msgs) sent += m.keyframes.size(), sub.apply(m);
  CHECK(sent == 49);  // i = 71 .. 119 moved more than 1 cm
  CHECK(sub.worst(current) <= 0.01 + 1e-12);

  // Keyframes leave the graph: announced in removed_ids.
  current.erase(current.begin() + 10, current.begin() + 40);
  msgs = feed.publish(5'000'000, current, Trajectory{});
  REQUIRE(!msgs.empty());
  size_t removed = 0;
  for (const auto& m : msgs) removed += m.removed_ids.size(), sub.apply(m);
  CHECK(removed == 30);
  CHECK(sub.size() == current.size());

  // The final flush: everything that differs at all, no budget.
  for (auto& k : current) k.pose.position.x() += 1e-6;
  for (const auto& m : feed.publish(5'100'000, current, Trajectory{}, true)) {
    CHECK(m.keyframes.size() <= 20);
    sub.apply(m);
  }
  CHECK(sub.worst(current) == 0.0);
}

TEST_CASE("trajectory feed: a late subscriber converges within one snapshot cycle, and messages stay small") {
  TrajectoryFeedOptions o;  // the defaults: 512 keyframes per message at most, snapshot chunks of 64
  TrajectoryFeed feed(o);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.002, 0.002);
  std::vector<Keyframe> current;
  Subscriber late;
  int64_t t = 0;
  int chunks_seen = 0, cycles_done = 0;
  bool joined = false;
  int64_t next_id = 0;
  for (int tick = 0; tick < 200; ++tick, t += 1'000'000) {
    for (int k = 0; k < 20; ++k, ++next_id) current.push_back(keyframe(next_id, next_id * 0.3, 0));
    for (auto& k : current) k.pose.position.y() += u(rng);  // small moves below the threshold pile up
    if (tick == 7) current.erase(current.begin() + 5, current.begin() + 25);
    const auto msgs = feed.publish(t, current, Trajectory{});
    for (const auto& m : msgs) {
      CHECK(m.keyframes.size() * 72 + m.removed_ids.size() * 8 <= 512 * 72);
      // Joins at tick 10, at the start of a snapshot cycle's message; holds nothing before.
      if (tick >= 10 && m.kind == Trajectory::Kind::kSnapshot && m.chunk == 0) joined = true;
      if (!joined) continue;
      late.apply(m);
      if (m.kind == Trajectory::Kind::kSnapshot) {
        ++chunks_seen;
        if (m.range_last == std::numeric_limits<int64_t>::max()) ++cycles_done;
      }
    }
    if (cycles_done >= 1) break;
  }
  REQUIRE(cycles_done == 1);
  // Every keyframe is held, within the move threshold (1 cm) of its current pose.
  CHECK(late.worst(current) <= o.move_translation);
  CHECK(chunks_seen >= 2);
}
