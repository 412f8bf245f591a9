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

}  // namespace

namespace {

/// One graph fed every robot, and three graphs, one per robot, exchanging contributions late and in bursts: robot c's
/// reach the others every 25 steps, a's and b's every 3 (and c hears late).  `together`: each burst applied by
/// apply_all (one solve per burst), else contribution by contribution.
struct ThreeRobotRun {
  std::unique_ptr<SlamGraph> single = std::make_unique<SlamGraph>(three_robot_options());
  std::vector<std::unique_ptr<SlamGraph>> graphs;
  int64_t exchange_updates = 0;  // the graphs' smoother updates while applying the others' contributions
  explicit ThreeRobotRun(bool together) {
    const auto world = random_landmarks(3, 30);
    Outbox single_out;
    std::vector<Outbox> outs(3);
    for (int k = 0; k < 3; ++k) graphs.push_back(std::make_unique<SlamGraph>(three_robot_options()));
    std::vector<size_t> delivered(9, 0);  // [from * 3 + to]: how much of from's outbox `to` has applied
    const auto deliver = [&](int to) {
      const int64_t before = graphs[to]->counters().updates;
      for (int from = 0; from < 3; ++from) {
        if (from == to) continue;
        auto& next = delivered[static_cast<size_t>(from * 3 + to)];
        const std::vector<GraphContribution> burst(outs[from].sent.begin() + static_cast<std::ptrdiff_t>(next),
                                                   outs[from].sent.end());
        next = outs[from].sent.size();
        if (together) {
          CHECK(graphs[to]->apply_all(burst, outs[to]) == static_cast<int>(burst.size()));
        } else {
          for (const GraphContribution& c : burst) CHECK(graphs[to]->apply(c, outs[to]));
        }
      }
      exchange_updates += graphs[to]->counters().updates - before;
    };
    for (int i = 0; i <= 200; ++i) {
      for (int k = 0; k < 3; ++k) {
        feed_three_robots(*single, k, i, world, single_out);
        feed_three_robots(*graphs[k], k, i, world, outs[k]);
      }
      for (int to = 0; to < 3; ++to)
        if (i % (to == 2 ? 25 : 3) == 0) deliver(to);
    }
    for (int to = 0; to < 3; ++to) deliver(to);
    for (int to = 0; to < 3; ++to) deliver(to);  // contributions made while applying (wholes completed by an owner)
  }
};

void check_three_robot_run(const ThreeRobotRun& run) {
  const SlamGraph& single = *run.single;
  CHECK(single.frames().size() == 1);
  for (const auto& g : run.graphs) {
    CHECK(g->frames().size() == 1);
    CHECK(g->counters().fleet_contributions_refused == 0);
    CHECK(g->counters().fleet_contributions_waiting == 0);
    for (const Robot& r : kThreeRobots) {
      CHECK(g->frame_of(r.name) == "a");
      CHECK(rms_between(g->keyframes(r.name), single.keyframes(r.name)) < 0.01);
    }
    CHECK(g->landmarks("a").size() == single.landmarks("a").size());
    // Which robot sightings were evidence before the join and which factors after depends on when they arrived.
    CHECK(std::abs(g->counters().fleet_sightings - single.counters().fleet_sightings) <= 3);
    CHECK(g->counters().fleet_loops == single.counters().fleet_loops);
  }
  CHECK(single.counters().fleet_loops == 1);
  CHECK(run.graphs[0]->remote("b"));
  CHECK(!run.graphs[0]->remote("a"));
}

}  // namespace

TEST_CASE(
    "contributions: three graphs, one per robot, exchanging contributions late and in bursts, end with the map one "
    "graph fed everything builds") {
  check_three_robot_run(ThreeRobotRun(false));
}

TEST_CASE("contributions: bursts applied together (apply_all) build the same map with one update per burst") {
  const ThreeRobotRun one_by_one(false), together(true);
  check_three_robot_run(together);
  for (size_t k = 0; k < 3; ++k)
    for (const Robot& r : kThreeRobots)
      CHECK(rms_between(together.graphs[k]->keyframes(r.name), one_by_one.graphs[k]->keyframes(r.name)) < 0.002);
  MESSAGE("smoother updates while applying: " << one_by_one.exchange_updates << " one by one, "
                                              << together.exchange_updates << " together");
  CHECK(together.exchange_updates * 4 < one_by_one.exchange_updates);
}

TEST_CASE("contributions: a local body's, a stream that skips a keyframe and a body without a first keyframe refused") {
  const auto world = random_landmarks(3, 30);
  SlamGraph a(three_robot_options()), b(three_robot_options());
  Outbox out_a, out_b;
  for (int i = 0; i <= 30; ++i) {
    feed_three_robots(a, 0, i, world, out_a);
    feed_three_robots(b, 1, i, world, out_b);
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
  b.add_odometry("a", odometry_at(kThreeRobots[0], 10), quiet);
  CHECK(b.counters().fleet_remote_inputs == 1);
}

TEST_CASE(
    "contributions: a graph holding a remote body and a waiting robot sighting saved and restored continues "
    "bit for bit") {
  const auto world = random_landmarks(3, 30);
  SlamGraph a(three_robot_options()), b(three_robot_options());
  Outbox out_a, out_b;
  for (int i = 0; i <= 40; ++i) {
    feed_three_robots(a, 0, i, world, out_a);
    feed_three_robots(b, 1, i, world, out_b);
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
  SlamGraph restored(three_robot_options());
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

namespace {

/// Three graphs, one per robot of kThreeRobots, and what each has applied of the others' contributions.
struct ThreeGraphs {
  std::vector<std::unique_ptr<SlamGraph>> graphs;
  std::vector<Outbox> outs = std::vector<Outbox>(3);
  size_t delivered[3][3] = {};
  ThreeGraphs() {
    for (int k = 0; k < 3; ++k) graphs.push_back(std::make_unique<SlamGraph>(three_robot_options()));
  }
  void deliver(int from, int to) {
    for (auto& next = delivered[from][to]; next < outs[static_cast<size_t>(from)].sent.size(); ++next)
      CHECK(graphs[static_cast<size_t>(to)]->apply(outs[static_cast<size_t>(from)].sent[next],
                                                   outs[static_cast<size_t>(to)]));
  }
  int64_t joins_made(int k) const {
    int64_t n = 0;
    for (const GraphContribution& c : outs[static_cast<size_t>(k)].sent) n += std::holds_alternative<FrameJoin>(c.what);
    return n;
  }
};

}  // namespace

TEST_CASE(
    "contributions: a frame joins only as its root's owner decides, and a graph that hears the joins in another "
    "order composes them into the same map") {
  const auto world = random_landmarks(3, 0);  // robot sightings only: which graph holds what evidence is controlled
  ThreeGraphs t;
  // b and c exchange; a is alone.  Both b's and c's graph hold the evidence between frames b and c; only c's owner
  // (the frame that moves: the later name) decides.
  for (int i = 0; i <= 100; ++i) {
    for (int k = 0; k < 3; ++k) feed_three_robots(*t.graphs[static_cast<size_t>(k)], k, i, world, t.outs[k]);
    t.deliver(1, 2), t.deliver(2, 1);
  }
  CHECK(t.joins_made(2) == 1);
  CHECK(t.joins_made(1) == 0);
  CHECK(t.graphs[1]->frame_of("c") == "b");
  CHECK(t.graphs[1]->counters().fleet_joins_remote == 1);
  // a's stream reaches b's and c's graphs, whose sightings of a place frame b (holding c) in a: b's owner decides,
  // c's graph follows.  a's graph holds evidence too (its own sightings of b and c) but hears nothing yet.
  t.deliver(0, 2);
  CHECK(t.graphs[2]->frame_of("c") == "b");  // the frame that would move is b's: c's graph does not decide
  t.deliver(0, 1);
  t.deliver(1, 2), t.deliver(2, 1);
  CHECK(t.joins_made(1) == 1);
  CHECK(t.graphs[2]->frame_of("c") == "a");
  CHECK(t.graphs[0]->frames().size() == 1);  // a's own frame only: it decides nothing for b
  // a's graph hears b's stream (b joins a) before c's (c joins b): it composes c's placement through b's.
  t.deliver(1, 0);
  CHECK(t.graphs[0]->frame_of("b") == "a");
  t.deliver(2, 0);
  for (int round = 0; round < 2; ++round)
    for (int from = 0; from < 3; ++from)
      for (int to = 0; to < 3; ++to)
        if (from != to) t.deliver(from, to);
  for (int k = 0; k < 3; ++k) {
    const SlamGraph& g = *t.graphs[static_cast<size_t>(k)];
    CHECK(g.frames().size() == 1);
    CHECK(g.counters().fleet_joins == 2);
    CHECK(g.counters().fleet_joins_remote == (k == 0 ? 2 : 1));
    CHECK(g.counters().fleet_joins_refused == 0);
    for (const Robot& r : kThreeRobots) {
      CHECK(g.frame_of(r.name) == "a");
      CHECK(rms_between(g.keyframes(r.name), t.graphs[1]->keyframes(r.name)) < 0.01);
      // In a's frame: a's first keyframe is the origin of a's odometry, so the truth maps by a's first pose.
      const auto kf = g.keyframes(r.name);
      const SE2 truth =
          kThreeRobots[0].truth(0).inverse() * r.truth(static_cast<double>(kf.back().utime - 1000000) / 1e6);
      CHECK((kf.back().pose.translation().head<2>() - truth.translation()).norm() < 0.05);
    }
  }
}

TEST_CASE(
    "contributions: lifelong thinning of a body is its owner's: every graph keeps the keyframes its owner keeps") {
  const auto world = random_landmarks(3, 30);
  ThreeGraphs t;
  for (int k = 0; k < 3; ++k) {
    SlamOptions o = three_robot_options();
    o.lifelong.planar = {120, 60};  // thinned many times over the run
    t.graphs[static_cast<size_t>(k)] = std::make_unique<SlamGraph>(o);
  }
  for (int i = 0; i <= 400; ++i) {
    for (int k = 0; k < 3; ++k) feed_three_robots(*t.graphs[static_cast<size_t>(k)], k, i, world, t.outs[k]);
    for (int to = 0; to < 3; ++to)  // c's graph hears late, in bursts: it thins at other moments than the others
      if (i % (to == 2 ? 25 : 3) == 0)
        for (int from = 0; from < 3; ++from)
          if (from != to) t.deliver(from, to);
  }
  for (int from = 0; from < 3; ++from)
    for (int to = 0; to < 3; ++to)
      if (from != to) t.deliver(from, to);
  const auto ids = [](const std::vector<KeyframeEstimate>& ks) {
    std::map<int64_t, Eigen::Vector3d> out;
    for (const auto& k : ks) out[k.id] = k.pose.translation();
    return out;
  };
  for (int owner = 0; owner < 3; ++owner) {
    const std::string body = kThreeRobots[owner].name;
    const auto kept = ids(t.graphs[static_cast<size_t>(owner)]->keyframes(body));
    CHECK(t.graphs[static_cast<size_t>(owner)]->counters().thinnings > 3);
    for (int g = 0; g < 3; ++g) {
      if (g == owner) continue;
      CAPTURE(body);
      CAPTURE(g);
      const auto here = ids(t.graphs[static_cast<size_t>(g)]->keyframes(body));
      // Every keyframe the owner kept is here; what is here beyond waits for this graph's next thinning, which takes
      // out only what the owner took out.
      double sum = 0;
      for (const auto& [id, p] : kept) {
        REQUIRE(here.contains(id));
        sum += (here.at(id) - p).squaredNorm();
      }
      CHECK(std::sqrt(sum / static_cast<double>(kept.size())) < 0.01);
      CHECK(here.size() - kept.size() <= 60);
    }
  }
}
