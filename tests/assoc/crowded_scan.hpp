#pragma once
// Crowded passive scans for the assoc tests: targets in a small box seen by up to four sensors, with misses and uniform
// clutter, so that many tuples compete (dense ghosts, large components).
#include "assoc/bearing_model.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace sextant::assoc::test {

/// `targets` targets uniform in [10, 12] x [10, 12] x [4, 5], seen by the first `sensors` (1-4) of four fixed sensors
/// with probability `pd` and 5 mrad noise, plus Poisson(`clutter`) false alarms per sensor uniform over the box's
/// bearings; each sensor's detections shuffled.
inline Scan crowded_scan(std::mt19937& rng, size_t sensors, int targets, double pd, double clutter) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.005);
  Scan scan;
  scan.sensors = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}, {30, 30, 0.1}};
  scan.sensors.resize(sensors);
  std::vector<Eigen::Vector3d> truth;
  for (int t = 0; t < targets; ++t) truth.push_back({10 + 2 * u(rng), 10 + 2 * u(rng), 4 + u(rng)});
  scan.detections.resize(sensors);
  for (size_t s = 0; s < sensors; ++s) {
    for (const auto& x : truth) {
      if (u(rng) > pd) continue;
      const auto h = *bearing(scan.sensors[s], x);
      scan.detections[s].push_back({h[0] + noise(rng), h[1] + noise(rng), 0.005, 0.005});
    }
    const auto lo = *bearing(scan.sensors[s], {10, 10, 4}), hi = *bearing(scan.sensors[s], {12, 12, 5});
    for (int k = 0; k < std::poisson_distribution<int>(clutter)(rng); ++k)
      scan.detections[s].push_back({std::min(lo[0], hi[0]) + std::abs(hi[0] - lo[0]) * u(rng),
                                    std::min(lo[1], hi[1]) + std::abs(hi[1] - lo[1]) * u(rng), 0.005, 0.005});
    std::shuffle(scan.detections[s].begin(), scan.detections[s].end(), rng);
  }
  return scan;
}

/// Detections per sensor.
inline std::vector<int> sizes(const Scan& s) {
  std::vector<int> n;
  for (const auto& d : s.detections) n.push_back(static_cast<int>(d.size()));
  return n;
}

}  // namespace sextant::assoc::test
