#include "sim/assoc_experiment.hpp"

#include "assoc/bearing_model.hpp"
#include "assoc/field_of_view.hpp"
#include "assoc/sd_assignment.hpp"
#include "daemon/runtime/nearest_rank_percentile.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <set>

#include <time.h>

namespace sextant::tools {
namespace {

double wrap(double a) {
  a = std::remainder(a, 2 * M_PI);
  return a <= -M_PI ? a + 2 * M_PI : a;
}

struct Box {
  Eigen::Vector3d lo, hi;
};

double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

std::vector<Eigen::Vector3d> assoc_experiment_sensors(int count) {
  std::vector<Eigen::Vector3d> s = {{30, 0, 0.1}, {0, 30, 0.1}, {0, 0, 0}, {30, 30, 0.1}, {15, -10, 0}, {-10, 15, 0.05}, {40, 15, 0.05}};
  s.resize(static_cast<size_t>(std::min(count, 7)));
  for (int k = 7; k < count; ++k) {
    const double a = 2 * M_PI * (k - 7) / (count - 7) + 0.3;
    s.push_back({15 + 30 * std::cos(a), 15 + 30 * std::sin(a), 0.1});
  }
  return s;
}

AssocExperimentResult run_assoc_experiment(const AssocExperimentOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, o.sigma);
  const auto sensors = assoc_experiment_sensors(o.sensors);
  // The grid layout (more than 2 targets).
  const int cols = static_cast<int>(std::ceil(std::sqrt(o.targets)));
  const int rows = (o.targets + cols - 1) / cols;
  Box region{{5, 5, 2}, {25 + (o.targets == 2 ? o.spacing : 0.0), 25, 8}};
  if (o.targets != 2 && !o.uniform_layout) {
    region.lo.x() = std::min(region.lo.x(), 15 - o.spacing * (cols - 1) / 2.0);
    region.hi.x() = std::max(region.hi.x(), 15 + o.spacing * (cols - 1) / 2.0);
    region.lo.y() = std::min(region.lo.y(), 15 - o.spacing * (rows - 1) / 2.0);
    region.hi.y() = std::max(region.hi.y(), 15 + o.spacing * (rows - 1) / 2.0);
  }
  std::vector<assoc::FieldOfView> fov;
  assoc::CostOptions co;
  co.kind = o.cost;
  co.alpha = o.alpha;
  co.p_detect = o.p_detect;
  for (const auto& s : sensors) {
    fov.push_back(assoc::field_of_view(s, region.lo, region.hi, 5 * o.sigma));
    co.sensor_clutter_density.push_back((o.clutter > 0 ? o.clutter : 0.1) / fov.back().area());
  }
  if (o.target_prior) co.target_density = o.targets / (region.hi - region.lo).prod();

  AssocExperimentResult r;
  double gap = 0, absolute_gap = 0, sq_err = 0, tuples = 0, iterations = 0;
  int scored = 0;  // scans scored (all but the exact solver's unproven ones)
  std::vector<double> ms, cpu_ms, build_ms;
  std::vector<std::pair<double, double>> per_run;  // (correct, observable) of every run
  int64_t err_n = 0;
  for (int run = 0; run < o.runs; ++run) {
    // Targets.
    std::vector<Eigen::Vector3d> truth;
    if (o.targets == 2) {
      const Eigen::Vector3d c(5 + 20 * unit(rng), 5 + 20 * unit(rng), 2 + 6 * unit(rng));
      truth = {c, c + Eigen::Vector3d(o.spacing, 0, 0)};
    } else if (o.uniform_layout) {
      for (int attempt = 0; static_cast<int>(truth.size()) < o.targets && attempt < 1000 * o.targets; ++attempt) {
        const Eigen::Vector3d x(5 + 20 * unit(rng), 5 + 20 * unit(rng), 2 + 6 * unit(rng));
        if (std::all_of(truth.begin(), truth.end(), [&](const Eigen::Vector3d& y) { return (x - y).norm() >= o.spacing; })) truth.push_back(x);
      }
    } else {
      for (int k = 0; k < o.targets; ++k)
        truth.push_back({15 + o.spacing * (k % cols - (cols - 1) / 2.0), 15 + o.spacing * (k / cols - (rows - 1) / 2.0), 5});
    }
    // Scans: detections shuffled, with their origin (target index or -1).
    assoc::Scan scan;
    scan.sensors = sensors;
    std::vector<std::vector<int>> origin(sensors.size());
    for (size_t s = 0; s < sensors.size(); ++s) {
      std::vector<std::pair<assoc::Detection, int>> list;
      for (size_t t = 0; t < truth.size(); ++t) {
        const auto h = *assoc::bearing(sensors[s], truth[t]);
        if (unit(rng) >= o.p_detect) continue;
        list.push_back({{h[0] + noise(rng), h[1] + noise(rng), o.sigma, o.sigma}, static_cast<int>(t)});
      }
      const int n_false = o.clutter > 0 ? std::poisson_distribution<int>(o.clutter)(rng) : 0;
      const auto& f = fov[s];
      for (int k = 0; k < n_false; ++k) {
        const double az = wrap(f.centre_azimuth + f.azimuth_lo + (f.azimuth_hi - f.azimuth_lo) * unit(rng));
        list.push_back({{az, f.elevation_lo + (f.elevation_hi - f.elevation_lo) * unit(rng), o.sigma, o.sigma}, -1});
      }
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
    int64_t observable = 0;
    for (const auto& t : tuple_of)
      if (std::count_if(t.begin(), t.end(), [](int k) { return k > 0; }) >= 2) true_tuples.insert(t), ++observable;
    // Associate.
    std::vector<int> sizes;
    for (const auto& d : scan.detections) sizes.push_back(static_cast<int>(d.size()));
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    const auto list = assoc::build_tuples(scan, co);
    const double c1 = thread_cpu_ms();
    const auto sol = o.exact ? assoc::solve_sd_exact(list, sizes)
                             : assoc::solve_sd_lagrangian(list, sizes, o.max_iterations, o.gap_tolerance);
    const double c2 = thread_cpu_ms();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cpu_ms.push_back(c2 - c0);
    build_ms.push_back(c1 - c0);
    if (o.exact && !sol.exact) {  // not proven optimal within the budget: counted, never scored as exact
      ++r.exact_unproven;
      continue;
    }
    if (o.compare_exact && !o.exact) {
      const auto best = assoc::solve_sd_exact(list, sizes);
      if (best.exact) {
        ++r.exact_compared;
        r.lr_optimal += std::abs(sol.cost - best.cost) <= 1e-6 * std::max(1.0, std::abs(best.cost));
      } else {
        ++r.exact_unproven;
      }
    }
    ++scored;
    r.observable_targets += observable;
    const int64_t correct_before = r.correct;
    gap += sol.gap;
    absolute_gap += sol.absolute_gap;
    r.gap_max = std::max(r.gap_max, sol.gap);
    iterations += sol.iterations;
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
    per_run.push_back({static_cast<double>(r.correct - correct_before), static_cast<double>(observable)});
  }
  const double n = std::max<double>(1, static_cast<double>(r.observable_targets));
  const double runs = std::max(1, scored);
  r.correct_rate = static_cast<double>(r.correct) / n;
  // Standard error of the ratio sum(correct) / sum(observable) over runs (the targets of one run are not
  // independent): sqrt(sum (c_i - R n_i)^2 / (k (k - 1))) / mean(n_i).
  if (per_run.size() > 1) {
    double ss = 0;
    for (const auto& [c, m] : per_run) ss += (c - r.correct_rate * m) * (c - r.correct_rate * m);
    const double k = static_cast<double>(per_run.size());
    r.correct_rate_stderr = std::sqrt(ss / (k * (k - 1))) / (n / k);
  }
  r.ghosts_per_scan = static_cast<double>(r.ghost_tuples) / runs;
  r.position_rmse = err_n ? std::sqrt(sq_err / static_cast<double>(err_n)) : 0.0;
  for (double m : ms) r.mean_ms += m / static_cast<double>(ms.size());  // every scan solved, proven or not
  r.median_ms = runtime::nearest_rank_percentile_of(ms, 0.5);
  r.p95_ms = runtime::nearest_rank_percentile_of(ms, 0.95);
  r.median_cpu_ms = runtime::nearest_rank_percentile_of(cpu_ms, 0.5);
  r.build_median_ms = runtime::nearest_rank_percentile_of(build_ms, 0.5);
  r.gap_mean = gap / runs;
  r.absolute_gap_mean = absolute_gap / runs;
  r.tuples_mean = tuples / runs;
  r.iterations_mean = iterations / runs;
  return r;
}

}  // namespace sextant::tools
