// Hostile values: valid messages (they decode, every number finite) whose values are physically impossible, through
// the intake (bytes, as the bus delivers them) into every stage of the engine.  Nothing published may be non-finite
// or carry an indefinite covariance, a clean body beside the hostile one must come out as it would alone, and no
// event may take longer than its budget.  The value fuzzer is short here (400 mutated messages); a longer run:
// SEXTANT_VALUE_FUZZ_MESSAGES=N build/bin/test_daemon -tc='value fuzzer*', and guided by coverage: `make fuzz`'s
// fuzz_values (tests/fuzz/values_fuzz.cpp, the same engine and mutations: hostile_engine.hpp).
#include "daemon/runtime/hostile_engine.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <random>

using namespace sextant;
using namespace sextant::hostile;

namespace {

// The clean body's poses must be those of a run without the hostile body (hostile::differing_poses).
void check_same(const std::vector<engine::FusedPose>& a, const std::vector<engine::FusedPose>& b) {
  REQUIRE(a.size() == b.size());
  CHECK(differing_poses(a, b) == 0);
}

// Replaces message `index` of `run` (counted among messages of `channel`) by `mutate(message)`.
template <class Msg, class F>
std::vector<Record> with_mutated(std::vector<Record> run, const std::string& channel, size_t index, F mutate) {
  size_t k = 0;
  for (auto& r : run) {
    if (r.channel != channel || k++ != index) continue;
    Msg m = decoded<Msg>(r);
    mutate(m);
    r.bytes = encoded(m);
    break;
  }
  return run;
}

}  // namespace

TEST_CASE("hostile values: each finding's message is refused at intake by its reason, and the body is unharmed") {
  const auto clean = simulated_run("robot1", 20, 3);
  struct Case {
    const char* name;
    const char* channel;
    const char* reason;
    std::vector<Record> run;
  };
  std::vector<Case> cases;
  cases.push_back({"odometry position 1e308", "ODOMETRY", "implausible_position",
                   with_mutated<sextant::odometry_t>(clean, "ODOMETRY", 300, [](auto& m) { m.position[0] = 1e308; })});
  cases.push_back({"increment covariance 1e300", "ODOMETRY", "implausible_covariance",
                   with_mutated<sextant::odometry_t>(clean, "ODOMETRY", 300, [](auto& m) {
                     m.has_increment_covariance = true;
                     for (int i = 0; i < 36; ++i) m.increment_covariance[i] = i % 7 == 0 ? 1e300 : 0;
                   })});
  cases.push_back({"planar odometry with roll 180 deg", "ODOMETRY", "implausible_tilt",
                   with_mutated<sextant::odometry_t>(clean, "ODOMETRY", 300, [](auto& m) {
                     m.orientation[0] = 0, m.orientation[1] = 1, m.orientation[2] = 0, m.orientation[3] = 0;
                   })});
  cases.push_back({"odometry jump of 100 m", "ODOMETRY", "implausible_speed",
                   with_mutated<sextant::odometry_t>(clean, "ODOMETRY", 300, [](auto& m) { m.position[0] += 100; })});
  cases.push_back({"sighting at range 1e308", "LANDMARKS", "implausible_range",
                   with_mutated<sextant::landmarks_t>(clean, "LANDMARKS", 30, [](auto& m) {
                     REQUIRE(m.num_observations > 0);
                     m.observations[0].range = 1e308;
                   })});
  Run reference;
  for (const auto& r : clean) reference.feed(r);
  for (const auto& c : cases) {
    CAPTURE(c.name);
    Run run;
    for (const auto& r : c.run) run.feed(r);
    CHECK(run.rejected(c.channel, c.reason) == 1);
    CHECK(run.unhealthy == 0);
    // One message less, the rest as the clean run: every estimator ends within a few centimetres of it.
    for (const char* estimator : {"dead_reckoning", "ekf", "graph"}) {
      CAPTURE(estimator);
      const auto last = [&](const Run& x) {
        engine::FusedPose p;
        for (const auto& q : x.poses)
          if (q.estimator == estimator) p = q;
        return p;
      };
      CHECK((last(run).pose.position - last(reference).pose.position).norm() < 0.2);
    }
  }
}

TEST_CASE(
    "hostile values: a consistent reset of a body's odometry is accepted after time_resync_messages and the body "
    "restarts") {
  auto run = simulated_run("robot1", 10, 4);
  size_t k = 0;
  for (auto& r : run) {
    if (r.channel != "ODOMETRY" || k++ < 200) continue;
    auto m = decoded<sextant::odometry_t>(r);
    m.position[0] += 500;  // the sender's odometry frame was reset 500 m away
    r.bytes = encoded(m);
  }
  Run x;
  for (const auto& r : run) x.feed(r);
  CHECK(x.rejected("ODOMETRY", "implausible_speed") == x.cfg.time_resync_messages);
  CHECK(x.unhealthy == 0);
  CHECK(x.of("robot1").back().utime > 0);
}

TEST_CASE(
    "value fuzzer: extreme finite values in every odometry, sighting and loop closure field of one body never harm "
    "the published poses or the other body") {
  const int messages =
      std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES") ? std::atoi(std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES")) : 400;
  const auto clean = simulated_run("clean", 20, 5);
  const auto victim = simulated_run("victim", 20, 6, false, /*loops=*/true);
  {  // the victim's loop closures, unharmed, reach its graph: the fuzzer's mutated ones are tried where it matters
    Run unharmed;
    for (const auto& r : victim) unharmed.feed(r);
    REQUIRE(unharmed.counter("graph", "loops_accepted") > 10);
  }
  for (bool pf : {false, true}) {
    CAPTURE(pf);
    Run alone(pf);
    for (const auto& r : clean) alone.feed(r);
    std::mt19937_64 rng(pf ? 11 : 7);
    const Choose choose = [&](size_t n) { return std::uniform_int_distribution<size_t>(0, n - 1)(rng); };
    int mutated = 0;
    const auto input = mixed(
        clean, victim, [&] { return rng() % 4 == 0; }, choose, messages, mutated);
    Run run(pf);
    for (const auto& r : input) run.feed(r);
    CHECK(mutated > 100);
    CHECK(run.unhealthy == 0);
    CHECK(run.max_event_ms < 2000);
    check_same(run.of("clean"), alone.of("clean"));
    CHECK(run.of("victim").size() > 100);
  }
}

TEST_CASE(
    "value fuzzer: extreme finite values in every IMU and GNSS field of one body (and its odometry and sightings) "
    "never harm the published poses, on the Earth too, or the other body") {
  const int messages =
      std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES") ? std::atoi(std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES")) : 400;
  const auto clean = simulated_run("clean", 20, 5, false, false, /*inertial=*/true);
  const auto victim = simulated_run("victim", 20, 6, false, false, /*inertial=*/true);
  Run alone(false, /*inertial=*/true);
  for (const auto& r : clean) alone.feed(r);
  REQUIRE(alone.geo_poses > 100);  // the inertial filter and smoother run, anchored by the fixes
  std::mt19937_64 rng(13);
  const Choose choose = [&](size_t n) { return std::uniform_int_distribution<size_t>(0, n - 1)(rng); };
  int mutated = 0;
  const auto input = mixed(
      clean, victim, [&] { return rng() % 4 == 0; }, choose, messages, mutated);
  Run run(false, /*inertial=*/true);
  for (const auto& r : input) run.feed(r);
  CHECK(mutated > 100);
  CHECK(run.unhealthy == 0);
  CHECK(run.max_event_ms < 2000);
  check_same(run.of("clean"), alone.of("clean"));
  const auto victim_poses = run.of("victim");
  CHECK(std::count_if(victim_poses.begin(), victim_poses.end(),
                      [](const engine::FusedPose& p) { return p.estimator == "inertial"; }) > 100);
}

TEST_CASE("bounded work: five landmark messages of 4096 unknown sightings each are handled in bounded time") {
  auto run = simulated_run("robot1", 6, 8, /*unknown_ids=*/true);
  Run x;
  int landmark_messages = 0;
  std::mt19937_64 rng(3);
  for (auto& r : run) {
    if (r.channel == "LANDMARKS" && landmark_messages < 5 && (++landmark_messages, true)) {
      auto m = decoded<sextant::landmarks_t>(r);
      const auto one = m.observations.at(0);
      m.observations.assign(4096, one);
      for (auto& o : m.observations) {
        o.id = -1;
        o.range = 1 + 10 * std::uniform_real_distribution<double>(0, 1)(rng);
        o.azimuth = std::uniform_real_distribution<double>(-3, 3)(rng);
      }
      m.num_observations = 4096;
      r.bytes = encoded(m);
    }
    x.feed(r);
  }
  CHECK(landmark_messages == 5);
  CHECK(x.unhealthy == 0);
  MESSAGE("largest event: " << x.max_event_ms << " ms in " << x.slowest);
  CHECK(x.max_event_ms < 3000);
}
