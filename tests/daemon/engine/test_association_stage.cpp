// The association stage on a simulated run: targets come out where the truth is, with few ghosts; the same with
// per-sensor false-alarm densities from the fields of view over a configured region and the target prior; and
// the configuration of those (errors name file:line).
#include "daemon/config/daemon_config.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "sim/simulator.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <string>

using namespace sextant;

namespace {

struct TargetScore {
  size_t scans = 0, truth = 0, found = 0, estimates = 0, ghosts = 0;
};

// Targets within 1 m of a true position (found) and estimates farther than 1 m from every truth (ghosts).
TargetScore score(const tools::ReplayResult& r) {
  TargetScore s;
  s.scans = r.targets.size();
  for (const auto& scan : r.targets) {
    std::vector<Eigen::Vector3d> truth;
    for (const auto& p : r.truth_points)
      if (p.kind == "target" && p.utime == scan.utime) truth.push_back(p.position);
    s.truth += truth.size();
    for (const auto& t : truth) {
      bool hit = false;
      for (const auto& e : scan.targets) hit = hit || (e.position - t).norm() < 1.0;
      s.found += hit;
    }
    for (const auto& e : scan.targets) {
      ++s.estimates;
      bool real = false;
      for (const auto& t : truth) real = real || (e.position - t).norm() < 1.0;
      s.ghosts += !real;
      CHECK(e.covariance.allFinite());
      CHECK(e.detection_indices.size() == scan.sensor_ids.size());
    }
    CHECK(scan.duality_gap >= 0);
  }
  return s;
}

// A 30 s simulated run (4 sensors, 4 targets, P_D 0.9, 1 false alarm per sensor and scan unless `o` says
// otherwise) replayed with `config`.
tools::ReplayResult replay_simulated(const config::DaemonConfig& config, tools::SimulationOptions o = {}) {
  const auto log =
      (std::filesystem::temp_directory_path() / ("sextant_assoc_" + std::to_string(::getpid()) + ".lcm")).string();
  o.duration_s = 30;
  o.seed = 5;
  {
    runtime::LogWriter w(log);
    tools::simulate(o, w);
  }
  auto r = tools::replay_log(log, config);
  std::remove(log.c_str());
  return r;
}

std::string error_of(const std::string& yaml) {
  try {
    config::parse_daemon_config(yaml, "test.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

// The simulator's targets stay within x in [-26, 26], y in [-18, 18], z in [4.5, 15.5] m.
const char* kRegion = "engine:\n  association:\n    region_min: [-30, -20, 4]\n    region_max: [30, 20, 16]\n";

}  // namespace

TEST_CASE("simulated bearing scans become targets at the true positions") {
  const auto s = score(replay_simulated(config::DaemonConfig{}));
  MESSAGE("targets found " << s.found << " of " << s.truth << "; ghosts " << s.ghosts << " of " << s.estimates);
  REQUIRE(s.scans >= 50);
  CHECK(s.found >= 0.9 * static_cast<double>(s.truth));
  CHECK(s.ghosts <= 0.2 * static_cast<double>(s.estimates));
}

TEST_CASE("per-sensor false-alarm densities over a region and the target prior: targets found, no more ghosts") {
  const auto plain = score(replay_simulated(config::DaemonConfig{}));
  const auto c = config::parse_daemon_config(std::string(kRegion) +
                                                 "    false_alarms_per_scan: 1\n    target_prior: true\n"
                                                 "    expected_targets: 4\n",
                                             "test.yaml");
  REQUIRE(c.engine.association.region_max == std::vector<double>{30, 20, 16});
  REQUIRE(c.engine.association.target_prior);
  const auto s = score(replay_simulated(c));
  MESSAGE("with region and prior: found " << s.found << " of " << s.truth << "; ghosts " << s.ghosts << " of "
                                          << s.estimates << " (scalar density, no prior: found " << plain.found
                                          << ", ghosts " << plain.ghosts << ")");
  REQUIRE(s.scans >= 50);
  CHECK(s.found >= 0.9 * static_cast<double>(s.truth));
  CHECK(s.ghosts <= plain.ghosts);
}

TEST_CASE(
    "false alarms simulated in the sensors' fields of view: targets still found, the region's density cuts ghosts") {
  // Two false alarms per sensor and scan inside the view of the targets' region (the simulator's clutter region,
  // the box the config names): they compete with the targets' detections, unlike clutter over all azimuths.
  tools::SimulationOptions o;
  o.clutter = 2;
  o.clutter_region_min = {-30, -20, 4}, o.clutter_region_max = {30, 20, 16};
  const auto plain = score(replay_simulated(config::DaemonConfig{}, o));
  const auto c = config::parse_daemon_config(std::string(kRegion) +
                                                 "    false_alarms_per_scan: 2\n    target_prior: true\n"
                                                 "    expected_targets: 4\n",
                                             "test.yaml");
  const auto s = score(replay_simulated(c, o));
  MESSAGE("clutter in view, region density and prior: found "
          << s.found << " of " << s.truth << ", ghosts " << s.ghosts << " of " << s.estimates
          << " (scalar density, no prior: found " << plain.found << ", ghosts " << plain.ghosts << " of "
          << plain.estimates << ")");
  REQUIRE(s.scans >= 50);
  CHECK(s.found >= 0.9 * static_cast<double>(s.truth));
  CHECK(s.ghosts <= 0.15 * static_cast<double>(s.estimates));
  CHECK(s.ghosts < plain.ghosts);
}

TEST_CASE("association region, false alarms and target prior: bad values are errors naming file:line") {
  CHECK(
      error_of(std::string(kRegion) + "    false_alarms_per_scan: 2\n    target_prior: true\n    expected_targets: 3\n")
          .empty());
  // region_max without region_min, at region_max's line.
  CHECK(error_of("engine:\n  association:\n    region_max: [1, 2, 3]\n")
            .find("test.yaml:3:17: 'engine.association.region_min' and") == 0);
  // Not three numbers.
  CHECK(error_of("engine:\n  association:\n    region_min: [1, 2]\n")
            .find("test.yaml:3:17: 'engine.association.region_min': expected [x, y, z]") == 0);
  // An empty box.
  CHECK(error_of("engine:\n  association:\n    region_min: [0, 0, 0]\n    region_max: [1, 0, 1]\n")
            .find("test.yaml:4:17: 'engine.association.region_max': must be above region_min on every axis (axis 1") ==
        0);
  // False alarms per scan or the prior without a region.
  CHECK(error_of("engine:\n  association:\n    false_alarms_per_scan: 2\n")
            .find("test.yaml:3:28: 'engine.association.false_alarms_per_scan': needs region_min") == 0);
  CHECK(error_of("engine:\n  association:\n    target_prior: true\n")
            .find("test.yaml:3:19: 'engine.association.target_prior': needs region_min") == 0);
  // Out of range.
  CHECK(error_of("engine:\n  association:\n    false_alarms_per_scan: -1\n").find("test.yaml:3:28:") == 0);
  CHECK(error_of(std::string(kRegion) + "    expected_targets: 0\n").find("test.yaml:5:23:") == 0);
  CHECK(error_of("engine:\n  association:\n    target_prior: maybe\n")
            .find("test.yaml:3:19: 'engine.association.target_prior': expected true or false") == 0);
}
