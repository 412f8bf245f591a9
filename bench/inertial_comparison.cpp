// The inertial estimators on simulated spatial runs (sim/inertial_comparison.hpp): odometry alone, the error-state
// filter and the keyframe smoother against the truth, one line per seed and the medians.
//   inertial_comparison [seeds=3] [duration_s=1200] [first_seed=1]
// Target (issue "Real robot sensors"): filter and graph position error during 60 s GNSS outages <= 0.5 x the odometry
// alone's; GNSS outliers do not pull the estimate by more than their sigma (0.5 m horizontal); the filter's NEES within
// its 95 % bounds: at each scored time the pose NEES averaged over the M seeds (ANEES, Bar-Shalom et al., "Estimation
// with Applications to Tracking and Navigation", 5.4.2) against [chi2(6M, 0.025), chi2(6M, 0.975)] / M.
#include "sim/inertial_comparison.hpp"

#include "assoc/chi_square.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace sextant::tools;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// The filter's ANEES over the seeds at each scored time, against its 95 % bounds.
void print_anees(const std::vector<std::vector<double>>& nees) {
  if (nees.empty()) return;
  size_t steps = nees.front().size();
  for (const auto& v : nees) steps = std::min(steps, v.size());
  const int m = static_cast<int>(nees.size());
  const double lower = sextant::assoc::chi2_quantile(6 * m, 0.025) / m,
               upper = sextant::assoc::chi2_quantile(6 * m, 0.975) / m;
  size_t inside = 0, above = 0;
  std::vector<double> anees(steps);
  for (size_t k = 0; k < steps; ++k) {
    for (const auto& v : nees) anees[k] += v[k] / m;
    inside += anees[k] >= lower && anees[k] <= upper ? 1 : 0;
    above += anees[k] > upper ? 1 : 0;
  }
  double mean = 0;
  for (double a : anees) mean += a / static_cast<double>(steps);
  std::printf(
      "filter pose NEES (6 dof) over %d seeds at %zu times: ANEES median %.2f, mean %.2f; 95 %% bounds [%.2f, %.2f]: "
      "inside at %.1f %% of the times, above at %.1f %%\n",
      m, steps, median(anees), mean, lower, upper, 100.0 * static_cast<double>(inside) / static_cast<double>(steps),
      100.0 * static_cast<double>(above) / static_cast<double>(steps));
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
  const double duration = argc > 2 ? std::atof(argv[2]) : 1200;
  const int first = argc > 3 ? std::atoi(argv[3]) : 1;
  std::printf(
      "| seed | ATE odometry / filter / smoother (m) | ATE in outages odometry / filter / smoother (m) | drift over a "
      "60 s "
      "outage odometry / filter / smoother (m) | worst horizontal error with GNSS filter / smoother (m) | outliers: "
      "simulated, filter gated, smoother down-weighted | time filter / smoother (s) | smoother per keyframe, first "
      "/ last 200 (ms) |\n|---|---|---|---|---|---|---|---|\n");
  std::vector<double> ratio_filter, ratio_smoother, drift_filter, drift_smoother;
  std::vector<std::vector<double>> nees;
  for (int s = first; s < first + seeds; ++s) {
    InertialComparisonOptions o;
    o.seed = static_cast<uint64_t>(s);
    o.duration_s = duration;
    const InertialComparison c = compare_inertial(o);
    std::printf(
        "| %d | %.3f / %.3f / %.3f | %.3f / %.3f / %.3f | %.3f / %.3f / %.3f | %.3f / %.3f | %lld, %lld, %lld | %.1f / "
        "%.1f | %.2f / %.2f |\n",
        s, c.odometry.ate, c.filter.ate, c.smoother.ate, c.odometry.ate_outage, c.filter.ate_outage,
        c.smoother.ate_outage, c.odometry.drift, c.filter.drift, c.smoother.drift, c.filter.worst_with_gnss,
        c.smoother.worst_with_gnss, static_cast<long long>(c.gnss_outliers), static_cast<long long>(c.filter_gated),
        static_cast<long long>(c.smoother_down_weighted), c.filter_seconds, c.smoother_seconds,
        1e3 * c.keyframe_cost_first, 1e3 * c.keyframe_cost_last);
    std::fflush(stdout);
    nees.push_back(c.filter_nees);
    ratio_filter.push_back(c.filter.ate_outage / c.odometry.ate_outage);
    ratio_smoother.push_back(c.smoother.ate_outage / c.odometry.ate_outage);
    drift_filter.push_back(c.filter.drift / c.odometry.drift);
    drift_smoother.push_back(c.smoother.drift / c.odometry.drift);
  }
  std::printf(
      "\nmedians over the seeds: ATE in outages / odometry's: filter %.2f, smoother %.2f; drift over an outage / "
      "odometry's: filter %.2f, smoother %.2f (goal <= 0.5)\n",
      median(ratio_filter), median(ratio_smoother), median(drift_filter), median(drift_smoother));
  print_anees(nees);
  return 0;
}
