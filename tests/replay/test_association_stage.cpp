// The association stage on a simulated run: targets come out where the truth is, with few ghosts.
#include "daemon/runtime/lcm_log.hpp"
#include "replay/replay_driver.hpp"
#include "replay/simulator.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>

using namespace sextant;

TEST_CASE("simulated bearing scans become targets at the true positions") {
  const auto log = (std::filesystem::temp_directory_path() / ("sextant_assoc_" + std::to_string(::getpid()) + ".lcm")).string();
  replay::SimulationOptions o;
  o.duration_s = 30;
  o.seed = 5;
  {
    runtime::LogWriter w(log);
    replay::simulate(o, w);
  }
  const auto r = replay::replay_log(log, config::DaemonConfig{});
  REQUIRE(r.targets.size() >= 50);
  size_t truth_count = 0, found = 0, estimates = 0, ghosts = 0;
  for (const auto& scan : r.targets) {
    std::vector<Eigen::Vector3d> truth;
    for (const auto& p : r.truth_points)
      if (p.kind == "target" && p.utime == scan.utime) truth.push_back(p.position);
    truth_count += truth.size();
    for (const auto& t : truth) {
      bool hit = false;
      for (const auto& e : scan.targets) hit = hit || (e.position - t).norm() < 1.0;
      found += hit;
    }
    for (const auto& e : scan.targets) {
      ++estimates;
      bool real = false;
      for (const auto& t : truth) real = real || (e.position - t).norm() < 1.0;
      ghosts += !real;
      CHECK(e.covariance.allFinite());
      CHECK(e.detection_indices.size() == scan.sensor_ids.size());
    }
    CHECK(scan.duality_gap >= 0);
  }
  MESSAGE("targets found " << found << " of " << truth_count << "; ghosts " << ghosts << " of " << estimates);
  CHECK(found >= 0.9 * static_cast<double>(truth_count));
  CHECK(ghosts <= 0.2 * static_cast<double>(estimates));
  std::remove(log.c_str());
}
