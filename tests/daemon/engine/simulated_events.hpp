#pragma once
// The input events of a simulated run as the engine receives them: the simulator writes a log, each record is
// decoded as the intake decodes its channel (odometry, landmarks, loop closures and, with `bearings`, bearing scans).
#include "daemon/engine/events.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "sim/simulator.hpp"

#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace sextant::test {

inline std::vector<engine::Event> simulated_events(const tools::SimulationOptions& sim, bool bearings = true) {
  const auto log = (std::filesystem::temp_directory_path() /
                    ("sextant_events_" + std::to_string(::getpid()) + "_" + tools::scenario_name(sim.scenario) + "_" +
                     sim.source + "_" + std::to_string(sim.seed) + ".lcm"))
                       .string();
  {
    runtime::LogWriter w(log);
    tools::simulate(sim, w);
  }
  const auto records = runtime::LogReader::read_all(log);
  std::remove(log.c_str());
  std::vector<engine::Event> events;
  for (const auto& r : records) {
    runtime::InputKind kind;
    if (r.channel == "ODOMETRY")
      kind = runtime::InputKind::kOdometry;
    else if (r.channel == "LANDMARKS")
      kind = runtime::InputKind::kLandmarks;
    else if (r.channel == "LOOP_CLOSURES")
      kind = runtime::InputKind::kLoopClosures;
    else if (r.channel == "BEARINGS" && bearings)
      kind = runtime::InputKind::kBearings;
    else
      continue;
    auto d = runtime::decode_event(kind, r.data.data(), r.data.size());
    if (auto* e = std::get_if<engine::Event>(&d)) events.push_back(*e);
  }
  return events;
}

}  // namespace sextant::test
