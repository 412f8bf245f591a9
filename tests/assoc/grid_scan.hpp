#pragma once
// Scans of the passive-association experiment's grid case for the assoc tests, drawn without the replay library.
#include "assoc/bearing_model.hpp"
#include "assoc/field_of_view.hpp"
#include "assoc/tuple_costs.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace sextant::assoc::test {

inline double wrap_angle(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

// The grid case of sim/assoc_experiment.hpp: the paper's three sensors (km), 20 targets on a 5 x 4 grid of
// spacing d km at z = 5 centred at (15, 15), P_D 0.9, sigma 5 mrad, Poisson(5) false alarms per sensor uniform in
// its field of view over [5, 25] x [5, 25] x [2, 8]; the costs' false-alarm density 5 / that field's area.  The
// same random draws as the experiment's: `rng` seeded as its --seed gives its scans in turn.
struct GridScan {
  Scan scan;
  CostOptions costs;
};

inline GridScan grid_scan(std::mt19937_64& rng, double spacing) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, 0.005);
  GridScan g;
  g.scan.sensors = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}};
  g.costs.p_detect = 0.9;
  const Eigen::Vector3d lo(5, 5, 2), hi(25, 25, 8);
  for (const auto& s : g.scan.sensors) {
    const FieldOfView f = field_of_view(s, lo, hi, 5 * 0.005);
    g.costs.sensor_clutter_density.push_back(5 / f.area());
    std::vector<Detection> d;
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d x(15 + spacing * (k % 5 - 2.0), 15 + spacing * (k / 5 - 1.5), 5);
      if (unit(rng) >= 0.9) continue;
      const auto h = *bearing(s, x);
      d.push_back({h[0] + noise(rng), h[1] + noise(rng), 0.005, 0.005});
    }
    for (int k = std::poisson_distribution<int>(5)(rng); k > 0; --k)
      d.push_back({wrap_angle(f.centre_azimuth + f.azimuth_lo + (f.azimuth_hi - f.azimuth_lo) * unit(rng)),
                   f.elevation_lo + (f.elevation_hi - f.elevation_lo) * unit(rng), 0.005, 0.005});
    std::shuffle(d.begin(), d.end(), rng);
    g.scan.detections.push_back(d);
  }
  return g;
}

}  // namespace sextant::assoc::test
