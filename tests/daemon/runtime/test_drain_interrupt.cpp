// The shutdown drain's bound holds while the graph stage is in the middle of a long solve: at the deadline the
// stage is interrupted (Stage::interrupt), its smoother ends the rebuild under way after the Gauss-Newton iteration
// it is in, and the state the stage then saves is valid (a fresh stage loads it and has the same keyframes and
// landmarks, every estimate finite).  Before, the drain waited for the whole solve.
//
// The long solve: a planar body's simulated odometry (a few hundred keyframes), then one sightings message of five
// new landmarks, which admits five factors at once: more than the smoother's update budget (1 here), so it rebuilds
// with `rebuild_iterations` Gauss-Newton iterations (a million here) and relinearization thresholds so small that
// no iteration counts as converged: a solve of minutes, each iteration a full relinearization and factorization.
#include "daemon/config/daemon_config.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/engine/simulated_events.hpp"
#include "daemon/runtime/stage_runner.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <thread>

using namespace sextant;
using namespace sextant::engine;

using sextant::stage_counters::counter;

namespace {

const Emit ignore = [](Output) {};

GraphConfig graph_config(bool long_solves) {
  const std::string smoother = long_solves ? "    smoother:\n      rebuild_iterations: 1000000\n"
                                             "      relinearize_translation: 1.0e-300\n"
                                             "      relinearize_rotation: 1.0e-300\n"
                                             "      min_update_factors: 1\n      max_update_factors: 1\n"
                                           : "";
  return config::parse_daemon_config("engine:\n  graph:\n    lifelong:\n      enabled: false\n" + smoother, "t")
      .engine.graph;
}

// A planar body's odometry (no sightings, no loops: every update admits one factor), handed to the stage directly.
int64_t feed_odometry(GraphStage& stage) {
  tools::SimulationOptions sim;
  sim.scenario = tools::Scenario::kPlanar;
  sim.source = "robot";
  sim.seed = 3;
  sim.duration_s = 120;
  int64_t last = 0;
  for (const Event& e : test::simulated_events(sim, false))
    if (const auto* o = std::get_if<Odometry>(&e)) {
      stage.handle(e, ignore);
      last = o->utime;
    }
  return last;
}

// Five landmarks never seen before, at the body's latest time.
LandmarkSightings new_landmarks(int64_t utime) {
  LandmarkSightings s;
  s.utime = utime;
  s.source = "robot";
  s.planar = true;
  for (int k = 0; k < 5; ++k) {
    LandmarkObservation o;
    o.id = 100 + k;
    o.range = 3.0 + k;
    o.azimuth = -0.6 + 0.3 * k;
    o.covariance = Eigen::Vector3d(0.01, 1e-4, 1e-4).asDiagonal();
    s.observations.push_back(o);
  }
  return s;
}

}  // namespace

TEST_CASE("the shutdown drain interrupts a graph solve in progress at its deadline, and the state saved is valid") {
  GraphStage stage(graph_config(true), std::make_shared<GraphCorrections>());
  const int64_t last = feed_odometry(stage);
  const size_t keyframes = stage.keyframes("robot").size();
  REQUIRE(keyframes > 100);

  runtime::StageRunner runner(stage, 16, ignore);
  runner.start();
  REQUIRE(runner.offer(runtime::QueuedEvent(new_landmarks(last), std::chrono::steady_clock::now())));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the solve is under way
  const auto t0 = std::chrono::steady_clock::now();
  const auto deadline = t0 + std::chrono::milliseconds(200);
  runner.drain_and_stop(deadline);
  const double past_deadline = std::chrono::duration<double>(std::chrono::steady_clock::now() - deadline).count();
  MESSAGE("drain ended " << past_deadline << " s after its deadline");
  CHECK(past_deadline < 1.0);  // one Gauss-Newton iteration on a few hundred keyframes: milliseconds
  CHECK(counter(runner.status().counters, "drain_interrupted") == 1);
  CHECK(counter(stage.counters(), "solves_interrupted") >= 1);

  // The state saved after the interrupted solve (a save rebuilds too, and ends early as well): a fresh stage loads
  // it and holds the same keyframes and the five landmarks, every estimate finite.
  archive::ArchiveWriter w;
  const auto save_begun = std::chrono::steady_clock::now();
  runner.with_stage([&](Stage& s) { s.save(w); });
  CHECK(std::chrono::steady_clock::now() - save_begun < std::chrono::seconds(1));
  const std::string saved = w.take();
  GraphStage restored(graph_config(false), std::make_shared<GraphCorrections>());
  archive::ArchiveReader r(saved.data(), saved.size(), "graph");
  restored.load(r);
  const std::vector<Keyframe> kept = restored.keyframes("robot");
  CHECK(kept.size() == keyframes);
  for (const Keyframe& k : kept) REQUIRE(k.pose.position.allFinite());
  const auto landmarks = restored.landmarks("robot");
  CHECK(landmarks.size() == 5);
  for (const GraphLandmark& l : landmarks) CHECK(l.position.allFinite());
}
