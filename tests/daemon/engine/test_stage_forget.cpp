// A forgotten body (daemon.source_idle_s, Stage::forget) leaves no per-body state behind in any stage: the graph
// drops its keyframes, landmarks and factors from the smoother (the other body's graph is rebuilt and goes on), the
// filters and dead reckoning their tracks; a body that speaks again after that starts afresh.
#include "daemon/engine/engine.hpp"
#include "daemon/engine/filter_stage.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "simulated_events.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <unistd.h>

using namespace sextant;
using namespace sextant::engine;

namespace {

// Odometry, landmarks and loops of a simulated planar run of body `source`.
std::vector<Event> run_of(const std::string& source, uint64_t seed, double seconds) {
  tools::SimulationOptions sim;
  sim.seed = seed;
  sim.duration_s = seconds;
  sim.source = source;
  return test::simulated_events(sim, false);
}

}  // namespace

TEST_CASE("forget: a body leaves the graph, the filters and dead reckoning, the other body goes on") {
  const auto a = run_of("a", 1, 40), b = run_of("b", 2, 60);
  std::vector<Event> both(a);
  both.insert(both.end(), b.begin(), b.end());
  std::stable_sort(both.begin(), both.end(),
                   [](const Event& x, const Event& y) { return event_utime(x) < event_utime(y); });
  const int64_t end_of_a = event_utime(a.back());

  Engine engine(EngineConfig{});
  auto* graph = dynamic_cast<GraphStage*>(engine.stages()[2].get());
  auto* filter = dynamic_cast<FilterStage*>(engine.stages()[1].get());
  REQUIRE(graph != nullptr);
  REQUIRE(filter != nullptr);
  size_t i = 0;
  for (; i < both.size() && event_utime(both[i]) <= end_of_a; ++i) engine.handle(both[i], [](Output) {});
  const auto kf_a = graph->keyframes("a").size(), kf_b = graph->keyframes("b").size();
  REQUIRE(kf_a > 20);
  REQUIRE(kf_b > 20);
  REQUIRE(!graph->landmarks("a").empty());
  REQUIRE(filter->ekf("a") != nullptr);
  const auto b_before = graph->keyframes("b");

  for (auto& s : engine.stages()) s->forget("a");
  CHECK(graph->keyframes("a").empty());
  CHECK(graph->landmarks("a").empty());
  CHECK(graph->graph_keyframes() == static_cast<int64_t>(kf_b));
  CHECK(graph->graph_landmarks() == static_cast<int64_t>(graph->landmarks("b").size()));
  // The smoother holds b's variables only (keyframes and landmarks), and only b's factors.
  const auto* smoother = graph->smoother(true);
  REQUIRE(smoother != nullptr);
  CHECK(smoother->graph().variables().size() == kf_b + graph->landmarks("b").size());
  CHECK(filter->ekf("a") == nullptr);
  // b's keyframes are where they were (a rebuild of b's own graph moves them by little).
  const auto b_after = graph->keyframes("b");
  REQUIRE(b_after.size() == b_before.size());
  for (size_t k = 0; k < b_after.size(); ++k)
    CHECK((b_after[k].pose.position - b_before[k].pose.position).norm() < 0.05);

  // b goes on: its keyframes grow and its poses are published.
  int64_t b_poses = 0;
  for (; i < both.size(); ++i)
    engine.handle(both[i], [&](Output o) {
      if (const auto* f = std::get_if<FusedPose>(&o); f && f->source == "b") ++b_poses;
    });
  CHECK(graph->keyframes("b").size() > kf_b + 10);
  CHECK(b_poses > 1000);
  // a speaks again: a new body, keyframe ids from 0.
  engine.handle(a.front(), [](Output) {});
  REQUIRE(graph->keyframes("a").size() == 1);
  CHECK(graph->keyframes("a")[0].id == 0);
}
