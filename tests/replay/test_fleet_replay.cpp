// A simulated fleet replayed through the engine (one daemon's view): every robot, each starting in its own odometry
// frame, ends in the first robot's frame; its keyframes are where the truth puts them in that frame (no alignment:
// the fleet frame is robot1's odometry frame); and wrong inter-robot loops do not fold the map.
#include "daemon/engine/trajectory_rebuild.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <unistd.h>

using namespace sextant;

namespace {

struct FleetRun {
  tools::SimulationSummary truth;
  tools::ReplayResult replay;
};

FleetRun replay_fleet(int robots, double wrong_loops) {
  const auto log = (std::filesystem::temp_directory_path() /
                    ("sextant_fleet_" + std::to_string(::getpid()) + "_" + std::to_string(robots) + ".lcm"))
                       .string();
  tools::SimulationOptions o;
  o.robots = robots;
  o.wrong_loops = wrong_loops;
  o.duration_s = 180;
  o.seed = 5;
  FleetRun run;
  {
    runtime::LogWriter w(log);
    run.truth = tools::simulate(o, w);
    w.flush();
  }
  config::DaemonConfig cfg;
  cfg.engine.graph.fleet.markers = run.truth.markers;
  cfg.engine.graph.propose_loops = false;
  tools::ReplayOptions ro;
  ro.max_kept = 0;  // everything: the trajectories too
  run.replay = tools::replay_log(log, cfg, {}, ro);
  std::remove(log.c_str());
  return run;
}

/// The largest distance, over every robot's final keyframes, between the keyframe and its truth in robot1's frame.
double worst_keyframe_error(const FleetRun& run) {
  std::map<std::string, engine::TrajectoryRebuild> rebuilt;
  for (const auto& t : run.replay.trajectories) rebuilt[t.source].add(t);
  const auto truth_at = [&](const std::string& body, int64_t utime) {
    const auto& samples = run.truth.fleet_truth.at(body);
    const auto it =
        std::lower_bound(samples.begin(), samples.end(), utime, [](const auto& s, int64_t t) { return s.first < t; });
    return SE3(it->second.orientation, it->second.position);
  };
  const SE3 origin = truth_at("robot1", run.truth.fleet_truth.at("robot1").front().first);
  double worst = 0;
  for (const auto& [body, r] : rebuilt)
    for (const auto& [id, k] : r.keyframes()) {
      const SE3 expected = origin.inverse() * truth_at(body, k.utime);
      worst = std::max(worst, (k.pose.position - expected.translation()).norm());
    }
  return worst;
}

}  // namespace

TEST_CASE("fleet replay: three robots in their own frames end in one, where the truth puts them") {
  const FleetRun run = replay_fleet(3, 0.0);
  REQUIRE(run.truth.robot_sightings > 0);
  std::map<std::string, std::string> frame;
  for (const auto& t : run.replay.trajectories) frame[t.source] = t.frame;
  REQUIRE(frame.size() == 3);
  for (const auto& [body, f] : frame) CHECK(f == "robot1");
  CHECK(worst_keyframe_error(run) < 0.5);
}

TEST_CASE("fleet replay: with a third of the inter-robot loops wrong, the map is not folded") {
  const FleetRun clean = replay_fleet(3, 0.0), wrong = replay_fleet(3, 0.3);
  REQUIRE(wrong.truth.wrong_loops > 0);
  CHECK(worst_keyframe_error(wrong) < 0.5);
  CHECK(worst_keyframe_error(wrong) < worst_keyframe_error(clean) + 0.1);
}
