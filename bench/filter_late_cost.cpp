// Cost of late measurements in the filter stage: a simulated planar run (60 s, seed 1) fed through the stage in
// order, and with every input delayed by a random lag (sightings up to LAG s, odometry up to LAG/4 s, history 0.5 s)
// so that late inputs are inserted and everything after them re-applied.  Prints the median over REPS repetitions of
// the wall time per input and the ratio late / in order.
// Usage: filter_late_cost [reps] [lag_s]
#include "daemon/engine/filter_stage.hpp"
#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "sim/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <unistd.h>

using namespace sextant;

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::stoi(argv[1]) : 5;
  const double lag = argc > 2 ? std::stod(argv[2]) : 0.4;
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_late_" + std::to_string(::getpid()) + ".lcm")).string();
  tools::SimulationOptions o;
  o.seed = 1;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  std::vector<engine::Event> events;
  for (const auto& r : runtime::LogReader::read_all(log)) {
    if (r.channel != "ODOMETRY" && r.channel != "LANDMARKS") continue;
    auto d =
        runtime::decode_event(r.channel == "ODOMETRY" ? runtime::InputKind::kOdometry : runtime::InputKind::kLandmarks,
                              r.data.data(), r.data.size());
    if (auto* e = std::get_if<engine::Event>(&d)) events.push_back(*e);
  }
  std::remove(log.c_str());
  std::mt19937 rng(1);
  std::vector<std::pair<int64_t, size_t>> arrival;
  for (size_t i = 0; i < events.size(); ++i) {
    const bool odo = std::holds_alternative<engine::Odometry>(events[i]);
    arrival.push_back({engine::event_utime(events[i]) + static_cast<int64_t>(std::uniform_real_distribution<double>(
                                                            0, (odo ? 0.25 : 1.0) * lag * 1e6)(rng)),
                       i});
  }
  std::stable_sort(arrival.begin(), arrival.end());
  engine::FilterConfig cfg;
  cfg.history_s = 0.5;
  const auto run = [&](bool late, int64_t* reapplied) {
    engine::FilterStage stage(cfg);
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t k = 0; k < events.size(); ++k)
      stage.handle(events[late ? arrival[k].second : k], [](engine::Output) {});
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() /
                      static_cast<double>(events.size());
    for (const auto& [name, v] : stage.counters())
      if (name == "late_reapplied") *reapplied = v;
    return us;
  };
  std::vector<double> in_order, late;
  int64_t reapplied = 0, none = 0;
  for (int r = 0; r < reps; ++r) {
    in_order.push_back(run(false, &none));
    late.push_back(run(true, &reapplied));
  }
  std::sort(in_order.begin(), in_order.end());
  std::sort(late.begin(), late.end());
  const double a = in_order[in_order.size() / 2], b = late[late.size() / 2];
  std::printf("inputs %zu, late re-applications %lld (lag up to %.2f s)\n", events.size(),
              static_cast<long long>(reapplied), lag);
  std::printf("median per input: in order %.1f us, late %.1f us, ratio %.2f\n", a, b, b / a);
  return 0;
}
