// The state directory's round trip, stage by stage (Stage::save / Stage::load): an engine fed a simulated run is saved
// half way; a fresh engine of the same config restored from those bytes and fed the rest publishes exactly what the
// saved engine publishes when it goes on (every number bit for bit): the graph (keyframes, loops, landmarks, lifelong
// thinning, MATCH_REQUESTS, TRAJECTORY and FUSED_POSE "graph"), the EKF and the 3-D EKF with their windows of late
// inputs, the particle filter, dead reckoning, the association's waiting scans.  A fresh engine fed the same rest publishes something else (the test can fail), and a
// damaged section is refused.
#include "daemon/engine/engine.hpp"
#include "simulated_events.hpp"

#include <doctest/doctest.h>

#include <cstring>
#include <random>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

using namespace sextant;
using namespace sextant::engine;

namespace {

std::vector<Event> simulated_events(const std::string& scenario, double seconds, uint64_t seed) {
  tools::SimulationOptions sim;
  sim.scenario = tools::scenario_from_name(scenario);
  sim.seed = seed;
  sim.duration_s = seconds;
  return test::simulated_events(sim);
}

// Every number and name of an output, in order: two output streams are the same when these are equal.
struct Flat {
  std::vector<double> numbers;
  std::string names;
  void pose(const Pose& p) {
    numbers.insert(numbers.end(), {p.position.x(), p.position.y(), p.position.z(), p.orientation.w(), p.orientation.x(),
                                   p.orientation.y(), p.orientation.z()});
  }
  void matrix(const Eigen::MatrixXd& m) { numbers.insert(numbers.end(), m.data(), m.data() + m.size()); }
  void add(const Output& o) {
    if (const auto* f = std::get_if<FusedPose>(&o)) {
      names += "F" + f->source + f->estimator;
      numbers.push_back(static_cast<double>(f->utime));
      pose(f->pose);
      matrix(f->covariance);
    } else if (const auto* t = std::get_if<Trajectory>(&o)) {
      names += "T" + t->source;
      numbers.insert(numbers.end(), {static_cast<double>(t->utime), t->chi2, static_cast<double>(t->iterations),
                                     static_cast<double>(t->kind), static_cast<double>(t->snapshot_id),
                                     static_cast<double>(t->chunk), static_cast<double>(t->total_keyframes)});
      for (const auto& k : t->keyframes) numbers.insert(numbers.end(), {double(k.id), double(k.utime)}), pose(k.pose);
      for (int64_t id : t->removed_ids) numbers.push_back(static_cast<double>(id));
    } else if (const auto* m = std::get_if<MatchRequest>(&o)) {
      names += "M" + m->source + m->kind;
      numbers.insert(numbers.end(), {double(m->utime), double(m->request_id), double(m->a.id), double(m->b.id)});
      pose(m->a.pose);
      pose(m->b.pose);
    } else if (const auto* g = std::get_if<Targets>(&o)) {
      names += "G";
      numbers.insert(numbers.end(), {double(g->utime), double(g->scan_id), g->total_cost});
    }
  }
};

std::vector<std::string> save_engine(Engine& e) {
  std::vector<std::string> sections;
  for (auto& s : e.stages()) {
    archive::ArchiveWriter w;
    s->save(w);
    sections.push_back(w.take());
  }
  return sections;
}

void load_engine(Engine& e, const std::vector<std::string>& sections) {
  REQUIRE(sections.size() == e.stages().size());
  for (size_t i = 0; i < sections.size(); ++i) {
    archive::ArchiveReader r(sections[i].data(), sections[i].size(), std::string(e.stages()[i]->name()));
    e.stages()[i]->load(r);
    CHECK(r.remaining() == 0);
  }
}

Flat feed(Engine& e, const std::vector<Event>& events, size_t from, size_t to) {
  Flat flat;
  for (size_t i = from; i < to; ++i) e.handle(events[i], [&](Output o) { flat.add(o); });
  e.finish([&](Output o) { flat.add(o); });
  return flat;
}

// Saves `config`'s engine after `half` of `events`, restores a fresh one and compares what both publish after.
void round_trip_at(const EngineConfig& config, const std::vector<Event>& events, size_t half,
                   size_t saved_bytes_at_least) {
  Engine saved(config);
  for (size_t i = 0; i < half; ++i) saved.handle(events[i], [](Output) {});
  const auto sections = save_engine(saved);
  size_t bytes = 0;
  for (const auto& s : sections) bytes += s.size();
  CHECK(bytes >= saved_bytes_at_least);
  const Flat expected = feed(saved, events, half, events.size());

  Engine restored(config);
  load_engine(restored, sections);
  const Flat got = feed(restored, events, half, events.size());
  REQUIRE(expected.numbers.size() > 1000);
  // The first difference, if any, with what was published there.
  size_t name_at = 0;
  while (name_at < std::min(got.names.size(), expected.names.size()) && got.names[name_at] == expected.names[name_at])
    ++name_at;
  const auto around = [&](const std::string& s) { return s.substr(name_at > 200 ? name_at - 200 : 0, 260); };
  CHECK_MESSAGE(got.names == expected.names, "first difference at character "
                                                 << name_at << " of " << expected.names.size() << "\n  saved:    "
                                                 << around(expected.names) << "\n  restored: " << around(got.names));
  size_t differ = 0, first = got.numbers.size();
  for (size_t i = 0; i < std::min(got.numbers.size(), expected.numbers.size()); ++i)
    if (std::memcmp(&got.numbers[i], &expected.numbers[i], sizeof(double)) != 0) ++differ, first = std::min(first, i);
  CHECK(got.numbers.size() == expected.numbers.size());
  CHECK_MESSAGE(differ == 0, differ << " numbers differ, the first at " << first << " of "
                                    << expected.numbers.size());  // bit for bit

  Engine fresh(config);
  const Flat cold = feed(fresh, events, half, events.size());
  CHECK((cold.names != expected.names || cold.numbers != expected.numbers));
}

void round_trip(const EngineConfig& config, const std::vector<Event>& events, size_t saved_bytes_at_least) {
  round_trip_at(config, events, events.size() / 2, saved_bytes_at_least);
}

EngineConfig lifelong_config() {
  EngineConfig c;
  c.primary_estimator = PrimaryEstimator::kGraph;
  c.graph.lifelong.planar.max_keyframes = 120;  // thinned several times before and after the save
  c.graph.lifelong.planar.window = 60;
  return c;
}

}  // namespace

TEST_CASE("state: a planar engine restored half way publishes what the saved one does, bit for bit") {
  const auto events = simulated_events("planar", 120, 3);
  round_trip(EngineConfig{}, events, 100000);
}

TEST_CASE("state: the graph restored after lifelong thinning continues identically") {
  const auto events = simulated_events("planar", 120, 4);
  round_trip(lifelong_config(), events, 100000);
}

TEST_CASE("state: a 3-D engine (3-D EKF, 3-D graph) restored half way publishes what the saved one does") {
  const auto events = simulated_events("spatial", 60, 5);
  round_trip(EngineConfig{}, events, 50000);
}

TEST_CASE(
    "state: the particle filter (FastSLAM, its maps and random generator) restored half way continues identically") {
  const auto events = simulated_events("planar", 60, 7);
  EngineConfig c;
  c.filter.type = FilterType::kPf;
  c.filter.pf.particles = 30;
  c.graph.enabled = false;
  c.association.enabled = false;
  round_trip(c, events, 20000);
}

TEST_CASE("state: saved at any moment (the first events included), every stage restores and continues identically") {
  // A property over save points: the first few events (the graph pose stage's ring of correction ages still
  // filling), then random ones.  Each is a full save / restore / continue round trip.
  const auto events = simulated_events("planar", 20, 9);
  EngineConfig config;
  config.primary_estimator = PrimaryEstimator::kGraph;
  std::mt19937_64 rng(5);
  REQUIRE(events.size() > 400);
  std::vector<size_t> points{1, 7, 200, events.size() * 3 / 4};
  for (int i = 0; i < 3; ++i) points.push_back(std::uniform_int_distribution<size_t>(1, events.size() / 2)(rng));
  for (size_t at : points) {
    CAPTURE(at);
    round_trip_at(config, events, at, 8);
  }
}

TEST_CASE("state: a damaged or truncated section is refused with the archive's name and offset") {
  const auto events = simulated_events("planar", 20, 6);
  EngineConfig config;
  Engine saved(config);
  for (const auto& e : events) saved.handle(e, [](Output) {});
  const auto sections = save_engine(saved);
  for (size_t i = 0; i < sections.size(); ++i) {
    if (sections[i].size() < 16) continue;
    const std::string name(saved.stages()[i]->name());
    Engine restored(config);
    const std::string cut = sections[i].substr(0, sections[i].size() / 2);
    archive::ArchiveReader r(cut.data(), cut.size(), "state (" + name + ")");
    bool threw = false;
    try {
      restored.stages()[i]->load(r);
      r.expect_end();
    } catch (const archive::ArchiveError& e) {
      threw = true;
      CHECK(std::string(e.what()).find("state (" + name + "): at byte ") == 0);
    }
    CHECK_MESSAGE(threw, name);
  }
}
