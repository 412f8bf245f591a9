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
  std::vector<Eigen::Vector3d> s = {{30, 0, 0.1}, {0, 30, 0.1},    {0, 0, 0},     {30, 30, 0.1},
                                    {15, -10, 0}, {-10, 15, 0.05}, {40, 15, 0.05}};
  s.resize(static_cast<size_t>(std::min(count, 7)));
  for (int k = 7; k < count; ++k) {
    const double a = 2 * M_PI * (k - 7) / (count - 7) + 0.3;
    s.push_back({15 + 30 * std::cos(a), 15 + 30 * std::sin(a), 0.1});
  }
  return s;
}

namespace {

// The experiment's runs: per run targets placed, a scan simulated (detections shuffled, false alarms in each
// sensor's field of view), associated and timed, the result scored against the true tuples; then the summary.  One
// random generator, drawn in the same order in every run.
class AssocExperiment {
 public:
  explicit AssocExperiment(const AssocExperimentOptions& o)
      : o_(o), rng_(o.seed), noise_(0, o.sigma), sensors_(assoc_experiment_sensors(o.sensors)) {
    lay_out();
  }

  AssocExperimentResult run() {
    for (int run = 0; run < o_.runs; ++run) {
      const std::vector<Eigen::Vector3d> truth = place_targets();
      std::vector<std::vector<int>> origin(sensors_.size());
      const assoc::Scan scan = simulate_scan(truth, origin);
      associate_and_score(scan, truth, origin);
    }
    return summarize();
  }

 private:
  // The grid layout (more than 2 targets), the region the targets and false alarms occupy, each sensor's field of
  // view over it and the cost options (clutter density per sensor from its field of view, the target prior).
  void lay_out() {
    cols_ = static_cast<int>(std::ceil(std::sqrt(o_.targets)));
    rows_ = (o_.targets + cols_ - 1) / cols_;
    Box region{{5, 5, 2}, {25 + (o_.targets == 2 ? o_.spacing : 0.0), 25, 8}};
    if (o_.targets != 2 && !o_.uniform_layout) {
      region.lo.x() = std::min(region.lo.x(), 15 - o_.spacing * (cols_ - 1) / 2.0);
      region.hi.x() = std::max(region.hi.x(), 15 + o_.spacing * (cols_ - 1) / 2.0);
      region.lo.y() = std::min(region.lo.y(), 15 - o_.spacing * (rows_ - 1) / 2.0);
      region.hi.y() = std::max(region.hi.y(), 15 + o_.spacing * (rows_ - 1) / 2.0);
    }
    co_.kind = o_.cost;
    co_.alpha = o_.alpha;
    co_.p_detect = o_.p_detect;
    for (const auto& s : sensors_) {
      fov_.push_back(assoc::field_of_view(s, region.lo, region.hi, 5 * o_.sigma));
      co_.sensor_clutter_density.push_back((o_.clutter > 0 ? o_.clutter : 0.1) / fov_.back().area());
    }
    if (o_.target_prior) co_.target_density = o_.targets / (region.hi - region.lo).prod();
  }

  // Two targets `spacing` apart at a random place, targets at random at least `spacing` apart, or the grid.
  std::vector<Eigen::Vector3d> place_targets() {
    std::vector<Eigen::Vector3d> truth;
    if (o_.targets == 2) {
      const Eigen::Vector3d c(5 + 20 * unit_(rng_), 5 + 20 * unit_(rng_), 2 + 6 * unit_(rng_));
      truth = {c, c + Eigen::Vector3d(o_.spacing, 0, 0)};
    } else if (o_.uniform_layout) {
      for (int attempt = 0; static_cast<int>(truth.size()) < o_.targets && attempt < 1000 * o_.targets; ++attempt) {
        const Eigen::Vector3d x(5 + 20 * unit_(rng_), 5 + 20 * unit_(rng_), 2 + 6 * unit_(rng_));
        if (std::all_of(truth.begin(), truth.end(),
                        [&](const Eigen::Vector3d& y) { return (x - y).norm() >= o_.spacing; }))
          truth.push_back(x);
      }
    } else {
      for (int k = 0; k < o_.targets; ++k)
        truth.push_back(
            {15 + o_.spacing * (k % cols_ - (cols_ - 1) / 2.0), 15 + o_.spacing * (k / cols_ - (rows_ - 1) / 2.0), 5});
    }
    return truth;
  }

  // Scans: detections shuffled, with their origin (target index or -1) in `origin`.
  assoc::Scan simulate_scan(const std::vector<Eigen::Vector3d>& truth, std::vector<std::vector<int>>& origin) {
    assoc::Scan scan;
    scan.sensors = sensors_;
    for (size_t s = 0; s < sensors_.size(); ++s) {
      std::vector<std::pair<assoc::Detection, int>> list;
      for (size_t t = 0; t < truth.size(); ++t) {
        const auto h = *assoc::bearing(sensors_[s], truth[t]);
        if (unit_(rng_) >= o_.p_detect) continue;
        list.push_back({{h[0] + noise_(rng_), h[1] + noise_(rng_), o_.sigma, o_.sigma}, static_cast<int>(t)});
      }
      const int n_false = o_.clutter > 0 ? std::poisson_distribution<int>(o_.clutter)(rng_) : 0;
      const auto& f = fov_[s];
      for (int k = 0; k < n_false; ++k) {
        const double az = wrap(f.centre_azimuth + f.azimuth_lo + (f.azimuth_hi - f.azimuth_lo) * unit_(rng_));
        list.push_back(
            {{az, f.elevation_lo + (f.elevation_hi - f.elevation_lo) * unit_(rng_), o_.sigma, o_.sigma}, -1});
      }
      std::shuffle(list.begin(), list.end(), rng_);
      std::vector<assoc::Detection> d;
      for (const auto& [det, org] : list) d.push_back(det), origin[s].push_back(org);
      scan.detections.push_back(std::move(d));
    }
    return scan;
  }

  // The scan associated (tuples built, then the S-D assignment), timed in wall and thread CPU time, and scored
  // against the true tuples (those of the targets seen by two sensors or more).
  void associate_and_score(const assoc::Scan& scan, const std::vector<Eigen::Vector3d>& truth,
                           const std::vector<std::vector<int>>& origin) {
    std::set<std::vector<int>> true_tuples;
    std::vector<std::vector<int>> tuple_of(truth.size(), std::vector<int>(sensors_.size(), 0));
    for (size_t s = 0; s < sensors_.size(); ++s)
      for (size_t k = 0; k < origin[s].size(); ++k)
        if (origin[s][k] >= 0) tuple_of[static_cast<size_t>(origin[s][k])][s] = static_cast<int>(k) + 1;
    int64_t observable = 0;
    for (const auto& t : tuple_of)
      if (std::count_if(t.begin(), t.end(), [](int k) { return k > 0; }) >= 2) true_tuples.insert(t), ++observable;
    std::vector<int> sizes;
    for (const auto& d : scan.detections) sizes.push_back(static_cast<int>(d.size()));
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    const auto list = assoc::build_tuples(scan, co_);
    const double c1 = thread_cpu_ms();
    const auto sol = o_.exact ? assoc::solve_sd_exact(list, sizes)
                              : assoc::solve_sd_lagrangian(list, sizes, o_.max_iterations, o_.gap_tolerance);
    const double c2 = thread_cpu_ms();
    ms_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cpu_ms_.push_back(c2 - c0);
    build_ms_.push_back(c1 - c0);
    if (o_.exact && !sol.exact) {  // not proven optimal within the budget: counted, never scored as exact
      ++r_.exact_unproven;
      return;
    }
    if (o_.compare_exact && !o_.exact) {
      const auto best = assoc::solve_sd_exact(list, sizes);
      if (best.exact) {
        ++r_.exact_compared;
        r_.lr_optimal += std::abs(sol.cost - best.cost) <= 1e-6 * std::max(1.0, std::abs(best.cost));
      } else {
        ++r_.exact_unproven;
      }
    }
    ++scored_;
    r_.observable_targets += observable;
    const int64_t correct_before = r_.correct;
    gap_ += sol.gap;
    absolute_gap_ += sol.absolute_gap;
    r_.gap_max = std::max(r_.gap_max, sol.gap);
    iterations_ += sol.iterations;
    tuples_ += static_cast<double>(list.size());
    for (int idx : sol.tuples) {
      const auto& tu = list[static_cast<size_t>(idx)];
      ++r_.output_tuples;
      if (true_tuples.count(tu.index)) {
        ++r_.correct;
        for (size_t t = 0; t < truth.size(); ++t)
          if (tuple_of[t] == tu.index) sq_err_ += (tu.position - truth[t]).squaredNorm(), ++err_n_;
      } else {
        ++r_.ghost_tuples;
      }
    }
    per_run_.push_back({static_cast<double>(r_.correct - correct_before), static_cast<double>(observable)});
  }

  // Rates, means over the scored scans, time percentiles over every scan.
  AssocExperimentResult summarize() {
    AssocExperimentResult& r = r_;
    const double n = std::max<double>(1, static_cast<double>(r.observable_targets));
    const double runs = std::max(1, scored_);
    r.correct_rate = static_cast<double>(r.correct) / n;
    // Standard error of the ratio sum(correct) / sum(observable) over runs (the targets of one run are not
    // independent): sqrt(sum (c_i - R n_i)^2 / (k (k - 1))) / mean(n_i).
    if (per_run_.size() > 1) {
      double ss = 0;
      for (const auto& [c, m] : per_run_) ss += (c - r.correct_rate * m) * (c - r.correct_rate * m);
      const double k = static_cast<double>(per_run_.size());
      r.correct_rate_stderr = std::sqrt(ss / (k * (k - 1))) / (n / k);
    }
    r.ghosts_per_scan = static_cast<double>(r.ghost_tuples) / runs;
    r.position_rmse = err_n_ ? std::sqrt(sq_err_ / static_cast<double>(err_n_)) : 0.0;
    for (double m : ms_) r.mean_ms += m / static_cast<double>(ms_.size());  // every scan solved, proven or not
    r.median_ms = runtime::nearest_rank_percentile_of(ms_, 0.5);
    r.p95_ms = runtime::nearest_rank_percentile_of(ms_, 0.95);
    r.median_cpu_ms = runtime::nearest_rank_percentile_of(cpu_ms_, 0.5);
    r.build_median_ms = runtime::nearest_rank_percentile_of(build_ms_, 0.5);
    r.gap_mean = gap_ / runs;
    r.absolute_gap_mean = absolute_gap_ / runs;
    r.tuples_mean = tuples_ / runs;
    r.iterations_mean = iterations_ / runs;
    return r;
  }

  const AssocExperimentOptions& o_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> unit_{0, 1};
  std::normal_distribution<double> noise_;
  const std::vector<Eigen::Vector3d> sensors_;
  int cols_ = 0, rows_ = 0;
  std::vector<assoc::FieldOfView> fov_;
  assoc::CostOptions co_;
  AssocExperimentResult r_;
  double gap_ = 0, absolute_gap_ = 0, sq_err_ = 0, tuples_ = 0, iterations_ = 0;
  int scored_ = 0;  // scans scored (all but the exact solver's unproven ones)
  std::vector<double> ms_, cpu_ms_, build_ms_;
  std::vector<std::pair<double, double>> per_run_;  // (correct, observable) of every run
  int64_t err_n_ = 0;
};

}  // namespace

AssocExperimentResult run_assoc_experiment(const AssocExperimentOptions& o) { return AssocExperiment(o).run(); }

}  // namespace sextant::tools
