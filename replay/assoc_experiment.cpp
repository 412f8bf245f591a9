#include "replay/assoc_experiment.hpp"

#include "assoc/bearing_model.hpp"
#include "assoc/sd_assignment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <set>

namespace sextant::replay {

AssocExperimentResult run_assoc_experiment(const AssocExperimentOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, o.sigma);
  std::vector<Eigen::Vector3d> sensors = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}};
  sensors.resize(static_cast<size_t>(std::min(o.sensors, 3)));
  for (int s = 3; s < o.sensors; ++s) {
    const double a = 2 * M_PI * (s - 3) / std::max(1, o.sensors - 3) + 0.4;
    sensors.push_back({15 + 30 * std::cos(a), 15 + 30 * std::sin(a), 0.5 * unit(rng)});
  }
  AssocExperimentResult r;
  double time_ms = 0, gap = 0, sq_err = 0, tuples = 0;
  int64_t err_n = 0;
  for (int run = 0; run < o.runs; ++run) {
    // Targets.
    std::vector<Eigen::Vector3d> truth;
    if (o.targets == 2) {
      const Eigen::Vector3d c(5 + 20 * unit(rng), 5 + 20 * unit(rng), 2 + 6 * unit(rng));
      truth = {c, c + Eigen::Vector3d(o.spacing, 0, 0)};
    } else {
      const int cols = static_cast<int>(std::ceil(std::sqrt(o.targets)));
      const int rows = (o.targets + cols - 1) / cols;
      for (int k = 0; k < o.targets; ++k)
        truth.push_back({15 + o.spacing * (k % cols - (cols - 1) / 2.0), 15 + o.spacing * (k / cols - (rows - 1) / 2.0), 5});
    }
    // Scans: detections shuffled, with their origin (target index or -1).
    assoc::Scan scan;
    scan.sensors = sensors;
    std::vector<std::vector<int>> origin(sensors.size());
    for (size_t s = 0; s < sensors.size(); ++s) {
      std::vector<std::pair<assoc::Detection, int>> list;
      double az_lo = 1e9, az_hi = -1e9, el_lo = 1e9, el_hi = -1e9;
      for (size_t t = 0; t < truth.size(); ++t) {
        const auto h = *assoc::bearing(sensors[s], truth[t]);
        az_lo = std::min(az_lo, h[0]), az_hi = std::max(az_hi, h[0]), el_lo = std::min(el_lo, h[1]), el_hi = std::max(el_hi, h[1]);
        if (unit(rng) >= o.p_detect) continue;
        list.push_back({{h[0] + noise(rng), h[1] + noise(rng), o.sigma, o.sigma}, static_cast<int>(t)});
      }
      const double pad = 5 * o.sigma;
      az_lo -= pad, az_hi += pad, el_lo -= pad, el_hi += pad;
      const int n_false = o.clutter > 0 ? std::poisson_distribution<int>(o.clutter)(rng) : 0;
      for (int k = 0; k < n_false; ++k)
        list.push_back({{az_lo + (az_hi - az_lo) * unit(rng), el_lo + (el_hi - el_lo) * unit(rng), o.sigma, o.sigma}, -1});
      std::shuffle(list.begin(), list.end(), rng);
      std::vector<assoc::Detection> d;
      for (const auto& [det, org] : list) d.push_back(det), origin[s].push_back(org);
      scan.detections.push_back(std::move(d));
    }
    // True tuples.
    std::set<std::vector<int>> true_tuples;
    std::vector<std::vector<int>> tuple_of(truth.size(), std::vector<int>(sensors.size(), 0));
    for (size_t s = 0; s < sensors.size(); ++s)
      for (size_t k = 0; k < origin[s].size(); ++k)
        if (origin[s][k] >= 0) tuple_of[static_cast<size_t>(origin[s][k])][s] = static_cast<int>(k) + 1;
    for (const auto& t : tuple_of)
      if (std::count_if(t.begin(), t.end(), [](int k) { return k > 0; }) >= 2) true_tuples.insert(t), ++r.observable_targets;
    // Associate.
    assoc::CostOptions co;
    co.kind = o.cost;
    co.alpha = o.alpha;
    co.p_detect = o.p_detect;
    co.clutter_density = 1e-3;
    if (o.clutter > 0) co.clutter_density = std::max(1e-3, o.clutter / std::pow(0.05, 2));  // a nominal 0.05 rad box
    std::vector<int> sizes;
    for (const auto& d : scan.detections) sizes.push_back(static_cast<int>(d.size()));
    const auto t0 = std::chrono::steady_clock::now();
    const auto list = assoc::build_tuples(scan, co);
    const auto sol = o.exact ? assoc::solve_sd_exact(list, sizes) : assoc::solve_sd_lagrangian(list, sizes);
    time_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    gap += sol.gap;
    tuples += static_cast<double>(list.size());
    for (int idx : sol.tuples) {
      const auto& tu = list[static_cast<size_t>(idx)];
      ++r.output_tuples;
      if (true_tuples.count(tu.index)) {
        ++r.correct;
        for (size_t t = 0; t < truth.size(); ++t)
          if (tuple_of[t] == tu.index) sq_err += (tu.position - truth[t]).squaredNorm(), ++err_n;
      } else {
        ++r.ghost_tuples;
      }
    }
  }
  const double n = std::max<double>(1, static_cast<double>(r.observable_targets));
  r.correct_rate = static_cast<double>(r.correct) / n;
  r.correct_rate_stderr = std::sqrt(r.correct_rate * (1 - r.correct_rate) / n);
  r.ghosts_per_scan = static_cast<double>(r.ghost_tuples) / std::max(1, o.runs);
  r.position_rmse = err_n ? std::sqrt(sq_err / static_cast<double>(err_n)) : 0.0;
  r.mean_ms = time_ms / std::max(1, o.runs);
  r.gap_mean = gap / std::max(1, o.runs);
  r.tuples_mean = tuples / std::max(1, o.runs);
  return r;
}

}  // namespace sextant::replay
