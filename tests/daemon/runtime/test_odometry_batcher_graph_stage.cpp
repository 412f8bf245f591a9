// One keyframe decision: the graph stage behind the daemon's stage thread and odometry batcher, lagging behind its
// input, builds the same graph as the same events handed to it directly (replay).  The runs are the simulator's,
// two bodies at 200 Hz (a planar one with a spike, a real jump and an indefinite increment covariance, the
// cases that needed the old coalescer's mirror of the keyframe selector kept in step; and a 3-D one), with their
// landmark sightings and loop closures.
#include "daemon/engine/graph_stage.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/pose_conversion.hpp"
#include "daemon/runtime/stage_runner.hpp"
#include "daemon/engine/simulated_events.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

const Emit ignore = [](Output) {};

// robot1 (planar) and robot2 (3-D), odometry at 200 Hz, in time order.  robot1's odometry: one message 20 m off (a
// spike), 5 s missing after 40 s and everything after re-initialized 0.5 m and 0.1 rad off (a real jump: the selector
// re-anchors), and at `drop_at` an indefinite increment covariance (the bus's intake refuses one; given directly,
// every estimator floors its eigenvalues, estimators/spd_matrix.hpp, so the keyframe stays).
std::vector<Event> two_bodies(int64_t drop_at) {
  tools::SimulationOptions a;
  a.scenario = tools::Scenario::kPlanar;
  a.source = "robot1";
  a.seed = 5;
  a.duration_s = 70;
  a.odometry_rate_hz = 200;
  tools::SimulationOptions b = a;
  b.scenario = tools::Scenario::kSpatial;
  b.source = "robot2";
  b.seed = 6;
  std::vector<Event> events = test::simulated_events(a, false), other = test::simulated_events(b, false);
  const int64_t t0 = event_utime(events.front());
  const SE3 reinit(SO3::exp(Eigen::Vector3d(0, 0, 0.1)), Eigen::Vector3d(0.5, -0.3, 0));
  std::vector<Event> kept;
  size_t odometry = 0;
  for (Event e : events) {
    if (auto* o = std::get_if<Odometry>(&e)) {
      const int64_t t = o->utime - t0;
      if (t >= 40'000'000 && t < 45'000'000) continue;
      if (t >= 45'000'000) o->pose = to_pose(reinit * to_se3(o->pose));
      if (++odometry == 1000) o->pose.position.x() += 20;
      if (o->utime == drop_at || o->utime == drop_at + 5000) {
        Matrix6 q = o->increment_covariance.value_or(Matrix6::Identity() * 1e-6);
        q(0, 0) = o->utime == drop_at ? -0.01 : 0.02;
        o->increment_covariance = q;
      }
    }
    kept.push_back(std::move(e));
  }
  std::vector<Event> out;
  std::merge(kept.begin(), kept.end(), other.begin(), other.end(), std::back_inserter(out),
             [](const Event& x, const Event& y) { return event_utime(x) < event_utime(y); });
  return out;
}

std::vector<Event> events_for(const Stage& stage, const std::vector<Event>& events) {
  std::vector<Event> out;
  for (const auto& e : events)
    if (stage.accepts(e)) out.push_back(e);
  return out;
}

// The same graph: every body's keyframes (times and poses) and landmarks, the stage's counters.
void check_same_graph(const GraphStage& live, const GraphStage& direct) {
  for (const std::string body : {"robot1", "robot2"}) {
    CAPTURE(body);
    const auto kl = live.keyframes(body), kd = direct.keyframes(body);
    REQUIRE(kl.size() == kd.size());
    for (size_t k = 0; k < kl.size(); ++k) {
      CHECK(kl[k].utime == kd[k].utime);
      CHECK(kl[k].pose.position == kd[k].pose.position);
      CHECK(kl[k].pose.orientation.coeffs() == kd[k].pose.orientation.coeffs());
    }
    const auto ll = live.landmarks(body), ld = direct.landmarks(body);
    REQUIRE(ll.size() == ld.size());
    for (size_t k = 0; k < ll.size(); ++k) {
      CHECK(ll[k].id == ld[k].id);
      CHECK(ll[k].sightings == ld[k].sightings);
      CHECK(ll[k].position == ld[k].position);
    }
  }
  const Counters cl = live.counters(), cd = direct.counters();
  REQUIRE(cl.size() == cd.size());
  for (size_t i = 0; i < cl.size(); ++i) {
    if (cl[i].first == "last_update_us" || cl[i].first.find("_us") != std::string::npos) continue;  // wall clock
    CHECK_MESSAGE(cl[i] == cd[i], cl[i].first);
  }
}

// A keyframe time of the planar body in the middle of the clean run: the message given the indefinite increment.
int64_t keyframe_to_drop() {
  const std::vector<Event> clean = two_bodies(-1);
  GraphStage stage(GraphConfig{}, std::make_shared<GraphCorrections>());
  for (const auto& e : events_for(stage, clean)) stage.handle(e, ignore);
  const auto kfs = stage.keyframes("robot1");
  REQUIRE(kfs.size() > 100);
  return kfs[kfs.size() / 4].utime;  // before the jump
}

}  // namespace

TEST_CASE("graph stage behind the odometry batcher, lagging: the keyframes and the graph of the direct feed") {
  const int64_t drop_at = keyframe_to_drop();
  GraphStage direct(GraphConfig{}, std::make_shared<GraphCorrections>());
  const std::vector<Event> events = events_for(direct, two_bodies(drop_at));
  size_t odometry = 0;
  for (const auto& e : events) odometry += std::holds_alternative<Odometry>(e) ? 1 : 0;
  for (const auto& e : events) direct.handle(e, ignore);
  direct.finish(ignore);  // as the runner's drain does
  // The cases the old mirror had to follow happened.
  CHECK(counter(direct, "keyframes_reanchored") == 1);
  CHECK(counter(direct, "keyframes_rejected") >= 10);      // the spike and the nine before the re-anchoring
  CHECK(counter(direct, "odometry_edges_rejected") == 0);  // the indefinite increment floored, its edge kept
  CHECK(counter(direct, "loops_accepted") > 10);
  CHECK(counter(direct, "sightings_accepted") > 100);

  runtime::OdometryBatcherOptions batching;  // the defaults: 256 messages a batch
  SUBCASE("the stage busy through the whole run (every event queued before it handles one)") {
    // Each sighting and loop takes a slot and closes its body's batch: 4096 slots hold the 70 s.
    GraphStage live(GraphConfig{}, std::make_shared<GraphCorrections>());
    runtime::StageRunner runner(live, 4096, ignore, batching);
    size_t refused = 0;
    for (const auto& e : events) refused += runner.offer({e, std::chrono::steady_clock::now()}) ? 0 : 1;
    const auto queued = runner.status();
    MESSAGE(events.size() << " events (" << odometry << " odometry) in " << queued.queue_depth << " queue slots");
    CHECK(refused == 0);
    CHECK(queued.queue_depth <= 2 * (events.size() - odometry) + 2);  // a slot per other event, a token after each
    CHECK(counter(queued, "odometry_waiting") == static_cast<int64_t>(odometry));
    runner.start();
    runner.drain_and_stop();
    CHECK(runner.status().processed == static_cast<int64_t>(events.size()));
    CHECK(counter(runner.status(), "odometry_waiting") == 0);
    check_same_graph(live, direct);

    // Without batching the same queue drops most of the run.
    GraphStage plain(GraphConfig{}, std::make_shared<GraphCorrections>());
    runtime::StageRunner unbatched(plain, 4096, ignore);
    for (const auto& e : events) unbatched.offer({e, std::chrono::steady_clock::now()});
    CHECK(unbatched.status().dropped > static_cast<int64_t>(events.size() / 2));
  }
  SUBCASE("the stage thread running, held now and then for 2000 events (a long solve)") {
    // The input as fast as the stage takes it (at most 400 slots queued, plus the 200 or so that 2000 events take:
    // the equivalence needs no drop), and every 3000 events the stage held while 2000 more arrive.
    GraphStage live(GraphConfig{}, std::make_shared<GraphCorrections>());
    runtime::StageRunner runner(live, 1024, ignore, batching);
    runner.start();
    size_t refused = 0, next = 0;
    auto offer = [&](size_t n, bool paced) {
      for (const size_t end = std::min(events.size(), next + n); next < end; ++next) {
        if (paced && next % 100 == 0)
          while (runner.status().queue_depth > 400) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        refused += runner.offer({events[next], std::chrono::steady_clock::now()}) ? 0 : 1;
      }
    };
    while (next < events.size()) {
      offer(3000, true);
      runner.with_stage([&](Stage&) { offer(2000, false); });  // the stage's thread waits meanwhile
    }
    runner.drain_and_stop();
    const auto s = runner.status();
    MESSAGE("odometry that joined a waiting batch: " << counter(s, "odometry_coalesced") << " of " << odometry);
    CHECK(refused == 0);
    CHECK(s.dropped == 0);
    CHECK(counter(s, "odometry_coalesced") > static_cast<int64_t>(odometry / 4));
    check_same_graph(live, direct);
  }
}
