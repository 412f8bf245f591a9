// A fleet daemon killed (no final save) and restarted from its state directory: two graph stages, one per robot,
// exchange their contributions (daemon/engine/fleet_exchange.hpp); one is dropped some time after its last save,
// while the other has applied what it sent since, and a new stage is loaded from that save.  It takes its tail back
// from the other before it contributes again, so both end with the same keyframes of both robots, at the same poses,
// and the other never sees the stream rewound.
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "estimators/slam/fleet_scenario.hpp"

#include <doctest/doctest.h>

#include <memory>
#include <set>
#include <tuple>

using namespace sextant;
using namespace sextant::engine;
using namespace sextant::slam::test;

namespace {

int64_t counter(const GraphStage& g, const std::string& name) {
  for (const auto& [n, v] : g.counters())
    if (n == name) return v;
  FAIL("no counter " << name);
  return 0;
}

GraphConfig fleet_config(const std::string& self) {
  GraphConfig c;
  static_cast<slam::SlamOptions&>(c) = three_robot_options();
  c.fleet_exchange.enabled = true;
  c.fleet_exchange.self = self;
  c.fleet_exchange.members = {"da", "db"};
  return c;
}

// Robot k's (0: a, 1: b of kThreeRobots) inputs at step i, 10 Hz odometry and 5 Hz sightings of the landmarks and
// of the other robot's marker, as the graph stage's events.  The sightings are stamped half-way to the next
// odometry message, so each waits for it (SlamGraph's early sightings): a save after an even step holds one.
std::vector<Event> inputs(int k, int i, const std::map<int64_t, Eigen::Vector2d>& world) {
  const Robot& r = kThreeRobots[k];
  const double t = 0.1 * i;
  const slam::OdometryInput in = odometry_at(r, t);
  std::vector<Event> out;
  out.push_back(Odometry{in.utime, r.name, true, to_pose(in.pose), in.covariance, in.increment_covariance, {}});
  if (i % 2 == 0) {
    auto points = world;
    points[k == 0 ? 1000 : 1001] = kThreeRobots[1 - k].truth(t + 0.05).translation();
    const slam::SightingsInput s = sightings_at(r, t + 0.05, points);
    LandmarkSightings e{s.utime, r.name, true, to_pose(SE3()), {}};
    for (const auto& o : s.sightings) e.observations.push_back({o.id, o.range, o.azimuth, o.elevation, o.covariance});
    out.push_back(std::move(e));
  }
  return out;
}

// Two daemons over a lossless bus: what one sends reaches the other at the next step.
struct Fleet {
  std::unique_ptr<GraphStage> stage[2];
  std::vector<Event> to[2];
  bool down[2] = {false, false};
  std::map<int64_t, slam::GraphContribution::What> sent_of_a;  // robot a's stream as its daemon sent it, by number

  Fleet() {
    for (int k = 0; k < 2; ++k) stage[k] = fresh(k);
  }
  static std::unique_ptr<GraphStage> fresh(int k) {
    return std::make_unique<GraphStage>(fleet_config(k == 0 ? "da" : "db"), std::make_shared<GraphCorrections>());
  }
  /// Step i: each daemon up takes the other's messages, its robot's inputs (when `feed`) and its tick.
  void step(int i, bool feed, const std::map<int64_t, Eigen::Vector2d>& world) {
    std::vector<Event> next[2];
    for (int k = 0; k < 2; ++k) {
      if (down[k]) continue;
      const Emit emit = [&, k](Output o) {
        if (auto* m = std::get_if<FleetContributions>(&o)) {
          for (size_t j = 0; k == 0 && m->body == "a" && j < m->contributions.size(); ++j)
            sent_of_a[m->first + static_cast<int64_t>(j)] = m->contributions[j];
          next[1 - k].push_back(std::move(*m));
        }
        if (auto* c = std::get_if<FleetControl>(&o)) next[1 - k].push_back(std::move(*c));
      };
      for (const Event& e : to[k]) stage[k]->handle(e, emit);
      if (feed)
        for (const Event& e : inputs(k, i, world)) stage[k]->handle(e, emit);
      FleetControl tick;
      tick.utime = 1000000 + int64_t{100000} * i;
      stage[k]->handle(tick, emit);
    }
    for (int k = 0; k < 2; ++k) to[k] = down[k] ? std::vector<Event>{} : std::move(next[k]);
  }
};

// The largest difference between two estimates of the same keyframes (the same ids required): translation (m) and
// rotation (rad, the angle of R1^T R2) together.
double largest_difference(const std::vector<Keyframe>& x, const std::vector<Keyframe>& y) {
  REQUIRE(x.size() == y.size());
  double worst = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    REQUIRE(x[k].id == y[k].id);
    const SE3 d = to_se3(x[k].pose).between(to_se3(y[k].pose));
    worst = std::max({worst, d.translation().norm(), d.rotation().log().norm()});
  }
  return worst;
}

}  // namespace

TEST_CASE(
    "graph stage: a fleet daemon killed after its last save and restarted from it ends with the same map as the "
    "other, and loses nothing of its robot's contributions") {
  const auto world = random_landmarks(3, 30);
  // Saved after step 100, while its robot's sightings of 10.05 s wait for the odometry of 10.1 s.
  constexpr int kSave = 101, kKill = 130, kRestart = 140, kEnd = 250;
  Fleet fleet, faultless;
  std::string saved;
  for (int i = 0; i <= kEnd + 100; ++i) {
    if (i == kSave) {
      archive::ArchiveWriter w;
      fleet.stage[0]->save(w);
      saved = w.data();
    }
    if (i == kKill) fleet.down[0] = true;  // no final save: what it did since kSave is gone with it
    if (i == kRestart) {
      fleet.stage[0] = Fleet::fresh(0);
      archive::ArchiveReader r(saved.data(), saved.size(), "state");
      fleet.stage[0]->load(r);
      r.expect_end();
      fleet.down[0] = false;
    }
    fleet.step(i, i <= kEnd, world);
    faultless.step(i, i <= kEnd, world);
  }
  const GraphStage& restarted = *fleet.stage[0];
  const GraphStage& other = *fleet.stage[1];
  CHECK(counter(restarted, "fleet_tail_adopted") > 0);
  CHECK(counter(restarted, "fleet_tail_waiting") == 0);
  CHECK(counter(other, "fleet_in_owner_rewound") == 0);
  CHECK(counter(other, "fleet_in_lost") == 0);
  CHECK(counter(other, "fleet_contributions_refused") == 0);
  CHECK(counter(restarted, "fleet_contributions_refused") == 0);
  CHECK(counter(other, "fleet_contributions_waiting") == 0);
  // b's sightings of a are completed by a's daemon (wholes in a's stream), each once: b's halves that it delivers
  // again to the restarted daemon (its state is older than they) do not make a second whole of what it took back.
  std::set<std::tuple<std::string, int64_t, int64_t>> wholes;
  for (const auto& [seq, what] : fleet.sent_of_a)
    if (const auto* w = std::get_if<slam::BodySighting>(&what))
      CHECK(wholes.emplace(w->observer, w->utime, w->sighting.id).second);
  CHECK(wholes.size() > 10);
  // Each sightings message of a is contributed once, anchored with a covariance (the restarted daemon's sightings
  // that waited for the odometry in its saved state were handled before the kill: they are in the tail it took back).
  std::set<int64_t> sightings;
  for (const auto& [seq, what] : fleet.sent_of_a)
    if (const auto* s = std::get_if<slam::SightingsContribution>(&what)) {
      CAPTURE(seq);
      CHECK(sightings.insert(s->sightings.utime).second);
      CHECK(s->anchor.covariance.diagonal().minCoeff() >= 0);
    }
  CHECK(fleet.sent_of_a.rbegin()->first == static_cast<int64_t>(fleet.sent_of_a.size()));  // 1, 2, ... all sent
  for (const char* body : {"a", "b"}) {
    CAPTURE(body);
    const auto mine = restarted.keyframes(body), theirs = other.keyframes(body);
    // Every keyframe made before the kill is there, with its id and time, as in the run without the fault (what
    // the robot sensed while its daemon was down reached no one).
    const auto reference = faultless.stage[1]->keyframes(body);
    size_t before_kill = 0;
    while (before_kill < reference.size() && reference[before_kill].utime < 1000000 + int64_t{100000} * kKill)
      ++before_kill;
    REQUIRE(mine.size() > before_kill);
    for (size_t k = 0; k < before_kill; ++k) {
      CHECK(mine[k].id == reference[k].id);
      CHECK(mine[k].utime == reference[k].utime);
    }
    for (size_t k = 1; k < mine.size(); ++k) CHECK(mine[k].id == mine[k - 1].id + 1);
    MESSAGE("largest difference restarted vs other: " << largest_difference(mine, theirs));
    CHECK(largest_difference(mine, theirs) < 1e-9);
    CHECK(restarted.landmarks(body).size() == other.landmarks(body).size());
  }
}
