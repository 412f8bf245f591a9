// Simulation and replay are deterministic: the same seed gives the same log, the same log the same outputs.
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"
#include "eval/trajectory_io.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

using namespace sextant;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("sextant_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

tools::SimulationSummary simulate_to(const std::string& path, const tools::SimulationOptions& o) {
  runtime::LogWriter w(path);
  auto s = tools::simulate(o, w);
  w.flush();
  return s;
}

tools::SimulationSummary simulate_to(const std::string& path, const std::string& scenario, uint64_t seed) {
  tools::SimulationOptions o;
  o.scenario = tools::scenario_from_name(scenario);
  o.seed = seed;
  o.duration_s = 12;
  return simulate_to(path, o);
}

}  // namespace

TEST_CASE("the same seed gives a byte-identical simulated log, another seed a different one") {
  for (const char* scenario : {"planar", "spatial"}) {
    const auto a = temp_path(std::string(scenario) + "_a.lcm"), b = temp_path(std::string(scenario) + "_b.lcm"),
               c = temp_path(std::string(scenario) + "_c.lcm");
    simulate_to(a, scenario, 7);
    simulate_to(b, scenario, 7);
    simulate_to(c, scenario, 8);
    CHECK(file_bytes(a) == file_bytes(b));
    CHECK(file_bytes(a) != file_bytes(c));
    CHECK(file_bytes(a).size() > 100000);
    for (const auto& p : {a, b, c}) std::remove(p.c_str());
  }
  // The scenario's spellings (`sextant simulate SCENARIO`): an unknown one names itself and the spellings.
  CHECK(tools::scenario_names() == std::vector<std::string>{"planar", "spatial"});
  CHECK(std::string(tools::scenario_name(tools::Scenario::kSpatial)) == "spatial");
  CHECK_THROWS_WITH_AS(tools::scenario_from_name("3d"), "unknown scenario '3d' (planar or spatial)",
                       std::invalid_argument);
}

TEST_CASE("replaying a log twice publishes the same bytes, and the ground truth is read back") {
  const auto log = temp_path("replay.lcm");
  const auto sim = simulate_to(log, "planar", 3);
  config::DaemonConfig cfg;
  const auto r1 = tools::replay_log(log, cfg);
  const auto r2 = tools::replay_log(log, cfg);
  REQUIRE(r1.published.size() == r2.published.size());
  bool same = true;
  for (size_t i = 0; i < r1.published.size(); ++i)
    same = same && r1.published[i].bytes == r2.published[i].bytes && r1.published[i].channel == r2.published[i].channel;
  CHECK(same);
  CHECK(r1.primary_estimator == "ekf");  // built-in defaults: every stage, the EKF on FUSED_POSE as config/default.yaml
  CHECK(r1.trajectories.size() > 10);
  CHECK(r1.match_requests.size() > 10);
  CHECK(r1.fused_poses.at("dead_reckoning").size() == static_cast<size_t>(sim.odometry));
  CHECK(r1.truth_poses.size() == sim.robot_truth.size());
  CHECK(r1.truth_points.size() > 0);
  // Dead reckoning starts on the truth and drifts only by the injected odometry noise (a few cm over 24 m).
  const auto& first = r1.fused_poses.at("dead_reckoning").front();
  CHECK((first.pose.position - sim.robot_truth.front().second.position).norm() < 1e-9);
  const auto& last = r1.fused_poses.at("dead_reckoning").back();
  const double drift = (last.pose.position - sim.robot_truth.back().second.position).norm();
  CHECK(drift > 1e-4);
  CHECK(drift < 3.0);
  std::remove(log.c_str());
}

TEST_CASE("replay orders by message utime, not by the log's stamps") {
  // Write odometry with log stamps in reverse order: replay must still process them by utime.
  const auto log = temp_path("reversed.lcm");
  const auto sim_log = temp_path("forward.lcm");
  simulate_to(sim_log, "planar", 5);
  auto records = runtime::LogReader::read_all(sim_log);
  {
    runtime::LogWriter w(log);
    int64_t stamp = 0;
    for (auto it = records.rbegin(); it != records.rend(); ++it)
      w.write_raw(++stamp, it->channel, it->data.data(), it->data.size());
  }
  config::DaemonConfig cfg;
  const auto forward = tools::replay_log(sim_log, cfg);
  const auto reversed = tools::replay_log(log, cfg);
  CHECK(reversed.channels.at("ODOMETRY").rejected == 0);
  CHECK(reversed.published.size() == forward.published.size());
  std::remove(log.c_str());
  std::remove(sim_log.c_str());
}

TEST_CASE("TUM files: written poses read back, and comments, commas, duplicates and bad rows") {
  const auto path = temp_path("traj.txt");
  std::vector<tools::StampedPose> poses(3);
  for (int i = 0; i < 3; ++i) {
    poses[i].t = 100.0 + i * 0.5;
    poses[i].pose.position = {1.0 * i, -2.0 * i, 0.25};
    poses[i].pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * i, Eigen::Vector3d::UnitZ()));
  }
  tools::write_tum(path, poses);
  const auto back = tools::read_tum(path);
  REQUIRE(back.size() == 3);
  CHECK(back[2].t == doctest::Approx(101.0));
  CHECK((back[2].pose.position - poses[2].pose.position).norm() < 1e-8);
  CHECK(back[2].pose.orientation.angularDistance(poses[2].pose.orientation) < 1e-8);
  {
    std::ofstream f(path);
    f << "# timestamp tx ty tz qx qy qz qw\n\n1.0,1,2,3,0,0,0,1\n2.0\t4 5 6 0 0 0 1\n1.0 7 8 9 0 0 0 1\n";
  }
  const auto mixed = tools::read_tum(path);
  REQUIRE(mixed.size() == 2);
  CHECK(mixed[0].pose.position.x() == 7);  // the later row with the same stamp wins
  {
    std::ofstream f(path);
    f << "1 2 3 4 0 0 0 1\n2 3 4 five 0 0 0 1\n";
  }
  CHECK_THROWS_WITH(tools::read_tum(path), doctest::Contains(":2: not a number: 'five'"));
  std::remove(path.c_str());
}

TEST_CASE("the graph's stages on a second thread publish what one thread publishes, in the same order") {
  // A fleet with sightings, robot sightings, inter-robot loops and lifelong thinning on a small budget: every kind of
  // graph output, and segments whose ends make the replay wait for the graph's thread before reading its counters.
  const auto log = temp_path("pipelined.lcm");
  tools::SimulationOptions o;
  o.robots = 3;
  o.duration_s = 60;
  o.seed = 11;
  const tools::SimulationSummary sim = simulate_to(log, o);
  config::DaemonConfig cfg;
  cfg.engine.graph.fleet.markers = sim.markers;
  cfg.engine.graph.lifelong.planar = {120, 60};
  tools::ReplayOptions ro;
  ro.segment_seconds = 7;
  ro.pipelined = false;
  const auto one = tools::replay_log(log, cfg, {}, ro);
  ro.pipelined = true;
  const auto two = tools::replay_log(log, cfg, {}, ro);
  std::remove(log.c_str());

  REQUIRE(one.published.size() > 1000);
  REQUIRE(one.published.size() == two.published.size());
  size_t first_difference = 0;
  while (first_difference < one.published.size() &&
         one.published[first_difference].channel == two.published[first_difference].channel &&
         one.published[first_difference].utime == two.published[first_difference].utime &&
         one.published[first_difference].bytes == two.published[first_difference].bytes)
    ++first_difference;
  INFO("first difference at message " << first_difference << " of " << one.published.size());
  CHECK(first_difference == one.published.size());
  // Every stage saw every event it accepts, and its processing times arrived in the same order (the kept samples).
  REQUIRE(one.stages.size() == two.stages.size());
  for (size_t i = 0; i < one.stages.size(); ++i) {
    INFO(one.stages[i].name);
    CHECK(one.stages[i].processed == two.stages[i].processed);
    CHECK(one.stages[i].latency_ms.size() == two.stages[i].latency_ms.size());
  }
  // The segments close at the same events, with the graph's counters as of then (its wall-clock times aside).
  REQUIRE(one.segments.size() == two.segments.size());
  CHECK(one.segments.size() >= 8);
  int64_t thinnings = 0;
  for (size_t s = 0; s < one.segments.size(); ++s) {
    for (size_t i = 0; i < one.segments[s].stages.size(); ++i)
      CHECK(one.segments[s].stages[i].events == two.segments[s].stages[i].events);
    const auto& a = one.segments[s].graph_counters;
    const auto& b = two.segments[s].graph_counters;
    REQUIRE(a.size() == b.size());
    for (size_t k = 0; k < a.size(); ++k) {
      if (a[k].first.ends_with("_us") || a[k].first.find("_us_") != std::string::npos) continue;
      INFO("segment " << s << ": " << a[k].first);
      CHECK(a[k].second == b[k].second);
      if (a[k].first == "thinnings") thinnings = a[k].second;
    }
  }
  CHECK(thinnings >= 1);
}
