// Lifelong operation, on a simulated run of many laps replayed through the daemon's engine with a small keyframe
// budget (so that the run is long relative to it and short for CI): the graph's size, the memory and the replay's
// work stay flat from the first quarter of the run to the last; loops to old places still close; the accuracy stays
// close to the full-history graph's; TRAJECTORY rebuilt from its messages equals the final keyframes.
#include "daemon/config/daemon_config.hpp"
#include "daemon/stage_counters.hpp"
#include "daemon/engine/trajectory_rebuild.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_eval.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <map>
#include <unistd.h>

using namespace sextant;

using sextant::stage_counters::counter;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

config::DaemonConfig graph_config(bool lifelong) {
  config::DaemonConfig cfg;
  cfg.engine.primary_estimator = engine::PrimaryEstimator::kGraph;
  cfg.engine.association.enabled = false;  // the graph alone (and dead reckoning)
  cfg.engine.filter.type = engine::FilterType::kNone;
  cfg.engine.graph.lifelong.enabled = lifelong;
  cfg.engine.graph.lifelong.planar.max_keyframes = 400;
  cfg.engine.graph.lifelong.planar.window = 200;
  // The odometry kept to bridge loop times to keyframes is bounded too, at 30000 poses by default (10 minutes at
  // 50 Hz): 120 s here, so that this run reaches its bound in its first quarter (loops to older times then land only
  // when their times are keyframes' own).
  cfg.engine.graph.odometry_history = 6000;
  return cfg;
}

double ate_of(const tools::ReplayResult& r) {
  std::vector<tools::StampedPose> truth, est;
  for (const auto& t : r.truth_poses) truth.push_back({static_cast<double>(t.utime) * 1e-6, t.pose});
  for (const auto& p : r.fused_poses.at("graph")) est.push_back({static_cast<double>(p.utime) * 1e-6, p.pose});
  return tools::absolute_trajectory_error(truth, est).error.rmse;
}

}  // namespace

TEST_CASE("lifelong: graph size and memory stay flat over a long run, loops still close, accuracy close to full") {
  // 480 s of laps (a lap of the simulator's 90 m course is 45 s): about 3200 keyframes, eight times the budget.
  const auto log = temp_path("lifelong.lcm");
  {
    tools::SimulationOptions o;
    o.duration_s = 480;
    o.seed = 4;
    o.sensors = 2;
    o.targets = 1;
    runtime::LogWriter w(log);
    tools::simulate(o, w);
    w.flush();
  }
  // Streamed as the command-line replay does: bounded samples in memory, the rest seen once.  A subscriber rebuilds
  // TRAJECTORY from the messages as they come, and the fused poses are kept compactly for the ATE.
  tools::ReplayOptions ro;
  ro.segment_seconds = 120;  // four quarters
  ro.max_kept = 1000;
  engine::TrajectoryRebuild rebuild;
  std::vector<tools::StampedPose> life_poses;  // every 10th (the ATE's sample; the memory check is the engine's)
  int64_t fused_seen = 0;
  ro.on_output = [&](const engine::Output& o) {
    if (const auto* p = std::get_if<engine::FusedPose>(&o); p && p->estimator == "graph" && fused_seen++ % 10 == 0)
      life_poses.push_back({static_cast<double>(p->utime) * 1e-6, p->pose});
    if (const auto* t = std::get_if<engine::Trajectory>(&o)) rebuild.add(*t);
  };
  const auto life = tools::replay_log(log, graph_config(true), {}, ro);
  REQUIRE(life.segments.size() == 4);
  for (const auto& seg : life.segments)
    MESSAGE("t " << seg.start_s << " s: graph keyframes " << counter(seg.graph_counters, "graph_keyframes")
                 << ", factors " << counter(seg.graph_counters, "graph_factors") << ", RSS " << seg.rss_kb << " KB");
  const auto& first = life.segments[0].graph_counters;
  const auto& last = life.segments[3].graph_counters;
  CHECK(counter(first, "thinnings") >= 1);
  CHECK(counter(last, "keyframes") > 3 * counter(first, "keyframes"));  // the run goes on ...
  // ... but the graph does not grow: within the budget plus the quarter added between two thinnings.
  for (const auto& seg : life.segments) {
    CHECK(counter(seg.graph_counters, "graph_keyframes") <= 400 + 100);
  }
  CHECK(counter(last, "graph_factors") <= 1.3 * static_cast<double>(counter(first, "graph_factors")));
  // Memory: flat from the second quarter (the first includes the start-up) to the last.
  REQUIRE(life.segments[1].rss_kb > 0);
  CHECK(static_cast<double>(life.segments[3].rss_kb) <= 1.10 * static_cast<double>(life.segments[1].rss_kb));

  // The full-history graph on the same run: loops close as often, and the fused pose is about as accurate.
  const auto full = tools::replay_log(log, graph_config(false));
  const auto graph_counters = [](const tools::ReplayResult& r) {
    for (const auto& s : r.stages)
      if (s.name == "graph") return s.counters;
    return engine::Counters{};
  };
  const int64_t loops_life = counter(graph_counters(life), "loops_accepted"),
                loops_full = counter(graph_counters(full), "loops_accepted");
  MESSAGE("loops accepted: lifelong " << loops_life << ", full " << loops_full);
  CHECK(loops_full > 50);
  CHECK(loops_life >= 0.9 * static_cast<double>(loops_full));
  std::vector<tools::StampedPose> truth;
  for (const auto& t : full.truth_poses) truth.push_back({static_cast<double>(t.utime) * 1e-6, t.pose});
  const double ate_life = tools::absolute_trajectory_error(truth, life_poses).error.rmse, ate_full = ate_of(full);
  MESSAGE("graph fused-pose ATE: lifelong " << ate_life << " m, full history " << ate_full << " m");
  CHECK(ate_life < 1.5 * ate_full);
  CHECK(ate_life < 0.1);

  // TRAJECTORY: the subscriber's rebuild equals the final keyframes (the ids the graph kept, their poses).
  const auto final_counters = graph_counters(life);
  CHECK(static_cast<int64_t>(rebuild.keyframes().size()) == counter(final_counters, "graph_keyframes"));
  CHECK(rebuild.total_keyframes() == static_cast<int>(rebuild.keyframes().size()));
  CHECK(life.trajectory_messages < 2 * 480 + 10);  // at most 1 Hz: an update and a snapshot chunk per publication
  std::remove(log.c_str());
}
