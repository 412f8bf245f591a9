// The inertial estimators on simulated spatial runs (sim/inertial_comparison.hpp): odometry alone, the error-state
// filter and the keyframe smoother against the truth, one line per seed and the medians.
//   inertial_comparison [seeds=3] [duration_s=1200] [first_seed=1]
// Target (issue "Real robot sensors"): filter and graph position error during 60 s GNSS outages <= 0.5 x the odometry
// alone's; GNSS outliers do not pull the estimate by more than their sigma (0.5 m horizontal).
#include "sim/inertial_comparison.hpp"

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
    ratio_filter.push_back(c.filter.ate_outage / c.odometry.ate_outage);
    ratio_smoother.push_back(c.smoother.ate_outage / c.odometry.ate_outage);
    drift_filter.push_back(c.filter.drift / c.odometry.drift);
    drift_smoother.push_back(c.smoother.drift / c.odometry.drift);
  }
  std::printf(
      "\nmedians over the seeds: ATE in outages / odometry's: filter %.2f, smoother %.2f; drift over an outage / "
      "odometry's: filter %.2f, smoother %.2f (goal <= 0.5)\n",
      median(ratio_filter), median(ratio_smoother), median(drift_filter), median(drift_smoother));
  return 0;
}
