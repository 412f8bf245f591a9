// EKF consistency on simulated planar runs (sim/filter_consistency.hpp): average pose NEES over seeds against
// the 95 % chi-square bounds, for localization with the known map and for EKF-SLAM; prints a table row per case
// and writes an SVG plot of ANEES over time.
// Usage: filter_consistency [runs] [duration_s] [svg_path]
#include "sim/filter_consistency.hpp"
#include "report/svg_plot.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

using namespace sextant;

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::stoi(argv[1]) : 20;
  const double duration = argc > 2 ? std::stod(argv[2]) : 60;
  const std::string svg = argc > 3 ? argv[3] : "";
  tools::SvgPlot plot("Pose ANEES over " + std::to_string(runs) + " runs (3 dof)", "time [s]", "ANEES");
  std::printf(
      "| case | runs | duration [s] | mean ANEES | 95 %% bounds | samples inside | final position RMSE [m] | wall [s] "
      "|\n|---|---|---|---|---|---|---|---|\n");
  for (const int kind : {0, 1, 2}) {  // localization, SLAM, 3-D SLAM
    const bool slam = kind > 0;
    tools::ConsistencyOptions o;
    o.runs = runs;
    o.slam = slam;
    if (kind == 2) o.simulation.scenario = tools::Scenario::kSpatial;
    o.simulation.duration_s = duration;
    o.every = 25;
    o.filter.initial_sigma_xy = 1e-3;
    o.filter.initial_sigma_theta = 1e-3;
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = tools::pose_nees_over_runs(o);
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const char* name = kind == 0 ? "EKF localization" : kind == 1 ? "EKF-SLAM" : "3-D EKF-SLAM (6 dof)";
    std::printf("| %s | %d | %.0f | %.2f | [%.2f, %.2f] | %.1f %% | %.3f | %.1f |\n", name, runs, duration,
                r.mean_anees, r.lower, r.upper, 100 * r.fraction_inside, r.final_position_rmse, wall);
    std::vector<Eigen::Vector2d> line, lo, hi;
    for (size_t i = 0; i < r.anees.size(); ++i) {
      line.push_back({r.time_s[i], r.anees[i]});
      lo.push_back({r.time_s[i], r.lower});
      hi.push_back({r.time_s[i], r.upper});
    }
    if (kind == 2) continue;  // 6 dof: another scale
    plot.polyline(line, slam ? "#d62728" : "#1f77b4", slam ? "EKF-SLAM" : "EKF localization");
    if (slam) {
      plot.polyline(lo, "#555555", "95 % bounds", 1.0);
      plot.polyline(hi, "#555555", "", 1.0);
    }
  }
  if (!svg.empty()) std::ofstream(svg) << plot.render();
  return 0;
}
