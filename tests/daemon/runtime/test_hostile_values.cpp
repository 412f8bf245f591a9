// Hostile values: valid messages (they decode, every number finite) whose values are physically impossible, through
// the intake (bytes, as the bus delivers them) into every stage of the engine.  Nothing published may be non-finite
// or carry an indefinite covariance, a clean body beside the hostile one must come out as it would alone, and no
// event may take longer than its budget.  The value fuzzer is short here (400 mutated messages); a longer run:
// SEXTANT_VALUE_FUZZ_MESSAGES=N build/bin/test_daemon -tc='value fuzzer*'.
#include "daemon/config/daemon_config.hpp"
#include "daemon/engine/engine.hpp"
#include "daemon/engine/guarded_handle.hpp"
#include "daemon/runtime/intake.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/filter/estimate_health.hpp"
#include "sim/simulator.hpp"
#include "daemon/runtime/encode_message.hpp"

#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>
#include <unistd.h>

using namespace sextant;

namespace {

struct Record {
  std::string channel;
  std::vector<uint8_t> bytes;
};

// A simulated planar run of `source` as the bus would carry it.
std::vector<Record> simulated_run(const std::string& source, double duration_s, uint64_t seed,
                                  bool unknown_ids = false) {
  tools::SimulationOptions sim;
  sim.duration_s = duration_s;
  sim.seed = seed;
  sim.source = source;
  sim.unknown_ids = unknown_ids;
  const auto path = (std::filesystem::temp_directory_path() /
                     ("sextant_hostile_" + std::to_string(::getpid()) + "_" + source + ".lcm"))
                        .string();
  {
    runtime::LogWriter w(path);
    tools::simulate(sim, w);
  }
  std::vector<Record> out;
  for (auto& r : runtime::LogReader::read_all(path))
    if (r.channel == "ODOMETRY" || r.channel == "LANDMARKS" || r.channel == "LOOP_CLOSURES" || r.channel == "BEARINGS")
      out.push_back({r.channel, std::vector<uint8_t>(r.data.begin(), r.data.end())});
  std::filesystem::remove(path);
  return out;
}

runtime::InputKind kind_of(const std::string& channel) {
  if (channel == "ODOMETRY") return runtime::InputKind::kOdometry;
  if (channel == "LANDMARKS") return runtime::InputKind::kLandmarks;
  if (channel == "BEARINGS") return runtime::InputKind::kBearings;
  return runtime::InputKind::kLoopClosures;
}

bool healthy(const engine::FusedPose& p) {
  Eigen::Matrix<double, 7, 1> x;
  x << p.pose.position, p.pose.orientation.coeffs();
  return filter::estimate_health(x, p.covariance, 6) == filter::Health::kHealthy && x.allFinite();
}

// The engine of config/default.yaml's defaults, with a particle filter in place of the EKF when `pf`.
struct Run {
  config::DaemonConfig cfg;
  runtime::ChannelStats stats;
  std::unique_ptr<runtime::Intake> intake;
  std::unique_ptr<engine::Engine> engine;
  std::vector<engine::FusedPose> poses;
  double max_event_ms = 0;
  std::string slowest;  // the stage of max_event_ms
  int unhealthy = 0;

  explicit Run(bool pf = false) {
    if (pf) cfg.engine.filter.type = engine::FilterType::kPf;
    cfg.engine.association.enabled = false;
    intake =
        std::make_unique<runtime::Intake>(stats, runtime::Intake::RejectHook{}, runtime::intake_options(cfg, false));
    for (const char* c : {"ODOMETRY", "LANDMARKS", "BEARINGS", "LOOP_CLOSURES"}) intake->add_channel(c, kind_of(c));
    engine = std::make_unique<engine::Engine>(cfg.engine);
  }
  void feed(const Record& r) {
    auto event = intake->accept(r.channel, r.bytes.data(), r.bytes.size(), runtime::Arrival::now());
    if (!event) return;
    const engine::Emit emit = [&](engine::Output o) {
      if (auto* p = std::get_if<engine::FusedPose>(&o)) {
        if (!healthy(*p)) ++unhealthy;
        poses.push_back(*p);
      }
    };
    if (!intake->resynced_body().empty())
      for (auto& s : engine->stages()) s->forget(intake->resynced_body());
    for (auto& s : engine->stages()) {
      if (!s->accepts(*event)) continue;
      const auto t0 = std::chrono::steady_clock::now();
      engine::handle_guarded(*s, *event, emit);
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      if (ms > max_event_ms) max_event_ms = ms, slowest = std::string(s->name());
    }
  }
  std::vector<engine::FusedPose> of(const std::string& source) const {
    std::vector<engine::FusedPose> out;
    for (const auto& p : poses)
      if (p.source == source) out.push_back(p);
    return out;
  }
  int64_t rejected(const std::string& channel, const std::string& reason) const {
    const auto s = stats.snapshot();
    auto it = s.at(channel).reasons.find(reason);
    return it == s.at(channel).reasons.end() ? 0 : it->second;
  }
};

template <class Msg>
Msg decoded(const Record& r) {
  Msg m;
  REQUIRE(m.decode(r.bytes.data(), 0, static_cast<int>(r.bytes.size())) == static_cast<int>(r.bytes.size()));
  return m;
}

// The clean body's poses must be those of a run without the hostile body: same count, same values.  The filters
// keep one estimate per body (equal to the last bit); the graph solves every body's keyframes in one smoother,
// whose relinearization points another body's factors move by rounding (micrometres).
void check_same(const std::vector<engine::FusedPose>& a, const std::vector<engine::FusedPose>& b) {
  REQUIRE(a.size() == b.size());
  int differ = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double tolerance = a[i].estimator == "graph" ? 1e-3 : 1e-9;
    differ += a[i].utime != b[i].utime || a[i].estimator != b[i].estimator ||
              (a[i].pose.position - b[i].pose.position).norm() > tolerance;
  }
  CHECK(differ == 0);
}

// Replaces message `index` of `run` (counted among messages of `channel`) by `mutate(message)`.
template <class Msg, class F>
std::vector<Record> with_mutated(std::vector<Record> run, const std::string& channel, size_t index, F mutate) {
  size_t k = 0;
  for (auto& r : run) {
    if (r.channel != channel || k++ != index) continue;
    Msg m = decoded<Msg>(r);
    mutate(m);
    r.bytes = encode(m);
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
    r.bytes = encode(m);
  }
  Run x;
  for (const auto& r : run) x.feed(r);
  CHECK(x.rejected("ODOMETRY", "implausible_speed") == x.cfg.time_resync_messages);
  CHECK(x.unhealthy == 0);
  CHECK(x.of("robot1").back().utime > 0);
}

namespace {

// Extreme but finite values: what a hostile or broken sender may put in any number.
double extreme(std::mt19937_64& rng) {
  static const double values[] = {1e308,  -1e308, 1e300, -1e300, 1e30, 1e15,    -1e15, 4.9e-324, -4.9e-324, 2.2e-308,
                                  1e-300, 0.0,    -0.0,  1.0,    -1.0, 3.14159, 1e6,   -1e6,     1e-12};
  return values[std::uniform_int_distribution<size_t>(0, std::size(values) - 1)(rng)];
}

template <class Msg>
void fuzz_doubles(Msg& m, std::mt19937_64& rng);

template <>
void fuzz_doubles(sextant::odometry_t& m, std::mt19937_64& rng) {
  std::vector<double*> fields;
  for (auto& v : m.position) fields.push_back(&v);
  for (auto& v : m.orientation) fields.push_back(&v);
  for (auto& v : m.covariance) fields.push_back(&v);
  for (auto& v : m.increment_covariance) fields.push_back(&v);
  for (auto& v : m.linear_velocity) fields.push_back(&v);
  for (auto& v : m.angular_velocity) fields.push_back(&v);
  for (auto& v : m.twist_covariance) fields.push_back(&v);
  const int n = std::uniform_int_distribution<int>(1, 3)(rng);
  for (int i = 0; i < n; ++i) *fields[std::uniform_int_distribution<size_t>(0, fields.size() - 1)(rng)] = extreme(rng);
  if (rng() % 4 == 0) m.has_increment_covariance = !m.has_increment_covariance;
  if (rng() % 8 == 0) m.utime += static_cast<int64_t>(rng() % 2 ? 1 : -1) * static_cast<int64_t>(rng() % 100'000'000);
}

template <>
void fuzz_doubles(sextant::landmarks_t& m, std::mt19937_64& rng) {
  if (m.num_observations == 0) return;
  auto& o = m.observations[rng() % static_cast<size_t>(m.num_observations)];
  std::vector<double*> fields{&o.range, &o.azimuth, &o.elevation};
  for (auto& v : o.covariance) fields.push_back(&v);
  for (auto& v : m.sensor_position) fields.push_back(&v);
  *fields[std::uniform_int_distribution<size_t>(0, fields.size() - 1)(rng)] = extreme(rng);
  if (rng() % 4 == 0) o.id = -1;
}

}  // namespace

TEST_CASE(
    "value fuzzer: extreme finite values in every odometry and sighting field of one body never harm the published "
    "poses or the other body") {
  const int messages =
      std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES") ? std::atoi(std::getenv("SEXTANT_VALUE_FUZZ_MESSAGES")) : 400;
  const auto clean = simulated_run("clean", 20, 5);
  const auto victim = simulated_run("victim", 20, 6);
  for (bool pf : {false, true}) {
    CAPTURE(pf);
    Run alone(pf);
    for (const auto& r : clean) alone.feed(r);
    // Interleave by time (both runs share the simulator's epoch) and mutate `messages` of the victim's.
    std::mt19937_64 rng(pf ? 11 : 7);
    std::vector<Record> mixed;
    size_t a = 0, b = 0;
    int mutated = 0;
    while (a < clean.size() || b < victim.size()) {
      if (b >= victim.size() || (a < clean.size() && a * victim.size() <= b * clean.size())) {
        mixed.push_back(clean[a++]);
        continue;
      }
      Record r = victim[b++];
      const bool hit = mutated < messages && rng() % 4 == 0;
      if (hit && r.channel == "ODOMETRY") {
        auto m = decoded<sextant::odometry_t>(r);
        fuzz_doubles(m, rng);
        r.bytes = encode(m);
        ++mutated;
      } else if (hit && r.channel == "LANDMARKS") {
        auto m = decoded<sextant::landmarks_t>(r);
        fuzz_doubles(m, rng);
        r.bytes = encode(m);
        ++mutated;
      }
      mixed.push_back(std::move(r));
    }
    Run run(pf);
    for (const auto& r : mixed) run.feed(r);
    CHECK(mutated > 100);
    CHECK(run.unhealthy == 0);
    CHECK(run.max_event_ms < 2000);
    check_same(run.of("clean"), alone.of("clean"));
    CHECK(run.of("victim").size() > 100);
  }
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
      r.bytes = encode(m);
    }
    x.feed(r);
  }
  CHECK(landmark_messages == 5);
  CHECK(x.unhealthy == 0);
  MESSAGE("largest event: " << x.max_event_ms << " ms in " << x.slowest);
  CHECK(x.max_event_ms < 3000);
}
