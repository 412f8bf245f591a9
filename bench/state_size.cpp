// The state directory's cost against run length (bench/RESULTS.md, "State directory"): a simulated run fed through
// the engine of config/default.yaml's defaults (lifelong on); every STEP minutes of data, every stage saves its state
// (Stage::save, what sextantd does between two events: for the graph stage this includes refactorizing its
// smoothers) and the state file is written as sextantd writes it (encode, temporary file, fsync, rename).  Prints,
// per step: data minutes, the state file's size and each stage's share, the time the stages took to save and the
// time to write, and the graph's size then.
// Usage: state_size [scenario planar|spatial] [minutes] [step_minutes] [seed]
#include "daemon/engine/engine.hpp"
#include "daemon/engine/graph_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "daemon/runtime/state_file.hpp"
#include "sim/simulator.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

using namespace sextant;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  const std::string scenario = argc > 1 ? argv[1] : "planar";
  const double minutes = argc > 2 ? std::stod(argv[2]) : 60;
  const double step = argc > 3 ? std::stod(argv[3]) : 5;
  const uint64_t seed = argc > 4 ? std::stoull(argv[4]) : 1;
  const auto dir = std::filesystem::temp_directory_path() / ("sextant_state_size_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string log = (dir / "run.lcm").string(), state = (dir / runtime::kStateFileName).string();
  tools::SimulationOptions sim;
  sim.scenario = tools::scenario_from_name(scenario);
  sim.seed = seed;
  sim.duration_s = minutes * 60;
  {
    runtime::LogWriter w(log);
    tools::simulate(sim, w);
  }
  engine::Engine engine(engine::EngineConfig{});
  const engine::GraphStage* graph = nullptr;
  for (const auto& s : engine.stages())
    if (auto* g = dynamic_cast<const engine::GraphStage*>(s.get())) graph = g;
  std::printf("%s, %.0f minutes, seed %llu, default engine config\n", scenario.c_str(), minutes,
              static_cast<unsigned long long>(seed));
  std::printf("%8s %12s %40s %10s %10s %10s %10s\n", "minutes", "file_bytes", "per stage (KB)", "save_ms", "write_ms",
              "keyframes", "factors");
  runtime::LogReader reader(log);
  int64_t start = -1, next = 0;
  const auto save = [&](int64_t utime) {
    const auto t0 = Clock::now();
    std::vector<runtime::StateSection> sections;
    for (auto& s : engine.stages()) {
      archive::ArchiveWriter w;
      s->save(w);
      sections.push_back({std::string(s->name()), w.take()});
    }
    const auto t1 = Clock::now();
    const std::string bytes = runtime::encode_state(1, sections);
    runtime::write_file_atomically(state, bytes);
    const auto t2 = Clock::now();
    std::string shares;
    for (const auto& s : sections) shares += s.name.substr(0, 5) + ":" + std::to_string(s.bytes.size() / 1024) + " ";
    std::printf("%8.1f %12zu %40s %10.1f %10.1f %10lld %10lld\n", static_cast<double>(utime - start) / 60e6,
                bytes.size(), shares.c_str(), std::chrono::duration<double, std::milli>(t1 - t0).count(),
                std::chrono::duration<double, std::milli>(t2 - t1).count(),
                static_cast<long long>(graph ? graph->graph_keyframes() : 0),
                static_cast<long long>(graph ? graph->graph_factors() : 0));
    std::fflush(stdout);
  };
  int64_t last = 0;
  while (auto r = reader.next()) {
    runtime::InputKind kind;
    if (r->channel == "ODOMETRY")
      kind = runtime::InputKind::kOdometry;
    else if (r->channel == "LANDMARKS")
      kind = runtime::InputKind::kLandmarks;
    else if (r->channel == "LOOP_CLOSURES")
      kind = runtime::InputKind::kLoopClosures;
    else if (r->channel == "BEARINGS")
      kind = runtime::InputKind::kBearings;
    else
      continue;
    auto d = runtime::decode_event(kind, r->data.data(), r->data.size());
    auto* e = std::get_if<engine::Event>(&d);
    if (e == nullptr) continue;
    const int64_t utime = engine::event_utime(*e);
    if (start < 0) start = utime, next = utime + static_cast<int64_t>(step * 60e6);
    if (utime >= next) {
      save(last);
      next += static_cast<int64_t>(step * 60e6);
    }
    engine.handle(*e, [](engine::Output) {});
    last = utime;
  }
  save(last);
  std::filesystem::remove_all(dir);
  return 0;
}
