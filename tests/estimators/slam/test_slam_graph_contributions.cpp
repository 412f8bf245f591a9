// One graph per robot, each fed only its own robot's inputs and the others' contributions (graph_contribution.hpp),
// against one graph fed everything: the same keyframes, frames and map.  And what apply() refuses.
#include "estimators/slam/fleet_scenario.hpp"
#include "estimators/slam/slam_graph.hpp"

#include <doctest/doctest.h>

#include <cstdlib>
#include <deque>
#include <memory>

using namespace sextant;
using namespace sextant::slam;
using namespace sextant::slam::test;

namespace {

/// Collects what a graph contributes, in order.
struct Outbox final : SlamListener {
  std::deque<GraphContribution> sent;
  void updated(const std::string&, int64_t, const graph::IncrementalStatus&) override {}
  void loop_proposed(const std::string&, int64_t, const KeyframeEstimate&, const KeyframeEstimate&, bool) override {}
  void contributed(const GraphContribution& c) override { sent.push_back(c); }
};

SlamOptions options() {
  SlamOptions o;
  o.propose_loops = false;
  o.fleet.markers = {{1000, "b"}, {1001, "a"}, {1002, "c"}};
  return o;
}

const Robot kRobots[] = {
    {"a", {0, 0}, 3, 0, 0.3}, {"b", {0.5, 0.5}, 2.5, 2.0, -0.25}, {"c", {-0.5, 0.2}, 2.8, 4.0, 0.2}};

/// Robot k's inputs at step i (10 Hz odometry, 5 Hz sightings of the shared landmarks and of the other robots), and
/// at step 60 an inter-robot loop from a to c.
void feed(SlamGraph& g, int k, int i, const std::map<int64_t, Eigen::Vector2d>& world, SlamListener& out) {
  const Robot& r = kRobots[k];
  const double t = 0.1 * i;
  g.add_odometry(r.name, odometry_at(r, t), out);
  if (i % 2 == 0) {
    auto points = world;
    for (int j = 0; j < 3; ++j)
      if (j != k) points[1000 + (j == 0 ? 1 : j == 1 ? 0 : 2)] = kRobots[j].truth(t).translation();
    g.add_sightings(r.name, sightings_at(r, t, points), out);
  }
  if (k == 0 && i == 60) {
    LoopInput l;
    l.utime_from = 5000000, l.utime_to = 5500000;  // a at 4 s, c at 4.5 s
    l.relative = (kRobots[0].truth(4).inverse() * kRobots[2].truth(4.5)).to_se3();
    l.information = Matrix6d::Identity() * 1e4;
    l.body_to = "c";
    g.add_loop("a", l, out);
  }
}

double rms_between(const std::vector<KeyframeEstimate>& x, const std::vector<KeyframeEstimate>& y) {
  REQUIRE(x.size() == y.size());
  double sum = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    CHECK(x[k].id == y[k].id);
    sum += (x[k].pose.translation() - y[k].pose.translation()).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(x.size()));
}

}  // namespace

TEST_CASE(
    "contributions: three graphs, one per robot, exchanging contributions late and in bursts, end with the map one "
    "graph fed everything builds") {
  const auto world = random_landmarks(3, 30);
  SlamGraph single(options());
  Outbox single_out;
  std::vector<std::unique_ptr<SlamGraph>> graphs;
  std::vector<Outbox> outs(3);
  for (int k = 0; k < 3; ++k) graphs.push_back(std::make_unique<SlamGraph>(options()));
  std::vector<size_t> delivered(9, 0);  // [from * 3 + to]: how much of from's outbox `to` has applied
  const auto deliver = [&](int to) {
    for (int from = 0; from < 3; ++from) {
      if (from == to) continue;
      auto& next = delivered[static_cast<size_t>(from * 3 + to)];
      for (; next < outs[from].sent.size(); ++next) CHECK(graphs[to]->apply(outs[from].sent[next], outs[to]));
    }
  };
  for (int i = 0; i <= 200; ++i) {
    for (int k = 0; k < 3; ++k) {
      feed(single, k, i, world, single_out);
      feed(*graphs[k], k, i, world, outs[k]);
    }
    // Robot c's contributions reach the others in bursts every 25 steps, a's and b's every 3 (and c hears late).
    for (int to = 0; to < 3; ++to)
      if (i % (to == 2 ? 25 : 3) == 0) deliver(to);
  }
  for (int to = 0; to < 3; ++to) deliver(to);
  for (int to = 0; to < 3; ++to) deliver(to);  // contributions made while applying (wholes completed by an owner)

  CHECK(single.frames().size() == 1);
  for (const auto& g : graphs) {
    CHECK(g->frames().size() == 1);
    CHECK(g->counters().fleet_contributions_refused == 0);
    CHECK(g->counters().fleet_contributions_waiting == 0);
    for (const Robot& r : kRobots) {
      CHECK(g->frame_of(r.name) == "a");
      CHECK(rms_between(g->keyframes(r.name), single.keyframes(r.name)) < 0.01);
    }
    CHECK(g->landmarks("a").size() == single.landmarks("a").size());
    // Which robot sightings were evidence before the join and which factors after depends on when they arrived.
    CHECK(std::abs(g->counters().fleet_sightings - single.counters().fleet_sightings) <= 3);
    CHECK(g->counters().fleet_loops == single.counters().fleet_loops);
  }
  CHECK(single.counters().fleet_loops == 1);
  CHECK(graphs[0]->remote("b"));
  CHECK(!graphs[0]->remote("a"));
}

TEST_CASE("contributions: a local body's, a stream that skips a keyframe and a body without a first keyframe refused") {
  const auto world = random_landmarks(3, 30);
  SlamGraph a(options()), b(options());
  Outbox out_a, out_b;
  for (int i = 0; i <= 30; ++i) {
    feed(a, 0, i, world, out_a);
    feed(b, 1, i, world, out_b);
  }
  // b's own body, claimed by a's contribution stream: refused, nothing changes.
  const auto before = b.keyframes("b").size();
  GraphContribution claim = out_b.sent.front();
  CHECK(b.apply(out_a.sent.front(), out_b));  // a's first keyframe: a new remote body in b
  CHECK_FALSE(b.apply(claim, out_b));
  CHECK(b.keyframes("b").size() == before);
  // A contribution that is not a keyframe, about a body b has never heard of: refused.
  GraphContribution stranger = out_a.sent[1];
  stranger.body = "z";
  CHECK_FALSE(b.apply(stranger, out_b));
  // A keyframe that does not follow the newest one (a gap in the stream): refused.
  GraphContribution skipped;
  for (const auto& c : out_a.sent)
    if (const auto* k = std::get_if<KeyframeContribution>(&c.what); k && k->id == 3) skipped = c;
  CHECK_FALSE(b.apply(skipped, out_b));
  CHECK(b.keyframes("a").size() == 1);
  CHECK(b.counters().fleet_contributions_refused == 3);
  // Inputs about a body another graph owns are refused too.
  Outbox quiet;
  b.add_odometry("a", odometry_at(kRobots[0], 10), quiet);
  CHECK(b.counters().fleet_remote_inputs == 1);
}

TEST_CASE(
    "contributions: a graph holding a remote body and a waiting robot sighting saved and restored continues "
    "bit for bit") {
  const auto world = random_landmarks(3, 30);
  SlamGraph a(options()), b(options());
  Outbox out_a, out_b;
  for (int i = 0; i <= 40; ++i) {
    feed(a, 0, i, world, out_a);
    feed(b, 1, i, world, out_b);
  }
  // b hears a's stream up to a robot sighting of b by a whose keyframe of a b has not heard yet: hold back a's newest
  // keyframe so that a whole sighting naming it waits.
  size_t cut = out_a.sent.size();
  for (size_t k = out_a.sent.size(); k-- > 0;)
    if (std::holds_alternative<KeyframeContribution>(out_a.sent[k].what)) {
      cut = k;
      break;
    }
  for (size_t k = 0; k < cut; ++k) b.apply(out_a.sent[k], out_b);
  archive::ArchiveWriter w;
  b.save(w);
  SlamGraph restored(options());
  archive::ArchiveReader r(w.data().data(), w.data().size(), "test");
  restored.load(r);
  CHECK(restored.remote("a"));
  CHECK(restored.counters().fleet_contributions_waiting == b.counters().fleet_contributions_waiting);
  Outbox quiet;
  for (size_t k = cut; k < out_a.sent.size(); ++k) {
    b.apply(out_a.sent[k], out_b);
    restored.apply(out_a.sent[k], quiet);
  }
  for (const char* body : {"a", "b"}) {
    const auto x = b.keyframes(body), y = restored.keyframes(body);
    REQUIRE(x.size() == y.size());
    for (size_t k = 0; k < x.size(); ++k) CHECK(x[k].pose.translation() == y[k].pose.translation());
  }
  CHECK(restored.counters().fleet_contributions_waiting == 0);
}
