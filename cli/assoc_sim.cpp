// sextant assoc-sim --sensors N --targets N --spacing D --sigma-mrad S [S ...] --runs R --cost C[,C...]|all
//                   --solver lr|exact|both [--pd P] [--clutter C] [--layout grid|uniform] [--target-prior]
//                   [--compare-exact] [--seed K]
//                   [--json] [--sweep-to D --step S --csv F]
// With --csv F, an SVG plot of the correct rate against d (one line per cost and solver) is written beside it for
// each sigma: F with ".csv" replaced by "_sigma<S>mrad.svg".
#include "sim/assoc_experiment.hpp"
#include "cli/command.hpp"
#include "report/json_writer.hpp"
#include "report/svg_plot.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

namespace {

using namespace sextant::tools;

struct Point {
  double sigma_mrad;
  std::string cost, solver;
  AssocExperimentOptions options;
  AssocExperimentResult result;
};

void put(JsonWriter& j, const Point& p) {
  const auto& r = p.result;
  j.field("sigma_mrad", p.sigma_mrad).field("cost", p.cost).field("solver", p.solver);
  j.field("spacing", p.options.spacing)
      .field("correct_rate", r.correct_rate)
      .field("correct_rate_stderr", r.correct_rate_stderr);
  j.field("observable_targets", r.observable_targets).field("ghosts_per_scan", r.ghosts_per_scan);
  j.field("position_rmse", r.position_rmse).field("mean_ms", r.mean_ms).field("median_ms", r.median_ms);
  j.field("p95_ms", r.p95_ms)
      .field("median_cpu_ms", r.median_cpu_ms)
      .field("build_median_ms", r.build_median_ms)
      .field("gap_mean", r.gap_mean);
  j.field("gap_max", r.gap_max).field("tuples_mean", r.tuples_mean).field("iterations_mean", r.iterations_mean);
  j.field("absolute_gap_mean", r.absolute_gap_mean);
  if (p.options.compare_exact) j.field("exact_compared", r.exact_compared).field("lr_optimal", r.lr_optimal);
  if (p.options.compare_exact || p.options.exact) j.field("exact_unproven", r.exact_unproven);
}

std::string svg_path(const std::string& csv, double sigma_mrad) {
  const std::string stem = csv.size() > 4 && csv.substr(csv.size() - 4) == ".csv" ? csv.substr(0, csv.size() - 4) : csv;
  std::ostringstream s;
  s << stem << "_sigma" << sigma_mrad << "mrad.svg";
  return s.str();
}

void write_plots(const std::string& csv, const std::vector<Point>& points, const std::vector<double>& sigmas) {
  static const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"};
  for (double sigma : sigmas) {
    const auto& o = points.front().options;
    std::ostringstream sub;
    sub << o.sensors << " sensors, " << o.targets << " targets, sigma " << sigma << " mrad, P_D " << o.p_detect << ", "
        << o.clutter << " false alarms/sensor" << (o.uniform_layout ? ", uniform" : "")
        << (o.target_prior ? ", target prior" : "");
    SvgPlot plot("Correct association rate", "target separation d [km]", "correct rate");
    plot.set_subtitle(sub.str());
    plot.set_legend_bottom(true);  // the rates rise with the separation: the bottom right is free
    std::vector<std::pair<std::string, std::string>> series;  // (cost, solver) in first-seen order
    for (const auto& p : points)
      if (p.sigma_mrad == sigma &&
          std::find(series.begin(), series.end(), std::make_pair(p.cost, p.solver)) == series.end())
        series.push_back({p.cost, p.solver});
    int color = 0;
    for (const auto& [cost, solver] : series) {
      std::vector<Eigen::Vector2d> line;
      for (const auto& p : points)
        if (p.sigma_mrad == sigma && p.cost == cost && p.solver == solver)
          line.push_back({p.options.spacing, p.result.correct_rate});
      const std::string label = cost + (solver == "exact" ? " (exact)" : " (LR)");
      plot.polyline(line, kColors[color % 6], label, solver == "exact" ? 1.0 : 1.8);
      plot.points(line, kColors[color % 6], "");
      ++color;
    }
    double d_max = 0;
    for (const auto& p : points) d_max = std::max(d_max, p.options.spacing);
    plot.set_view(-0.03 * std::max(d_max, 1e-3), 1.03 * std::max(d_max, 1e-3), -0.03, 1.05);  // rates in [0, 1]
    std::ofstream f(svg_path(csv, sigma));
    f << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" << plot.render() << "\n";
  }
}

// The command's arguments.
struct Args {
  AssocExperimentOptions o;
  std::vector<double> sigmas{5};
  double sweep_to = -1, step = 0.1;
  std::string costs = "classic", solver = "lr", csv, layout = "grid";
  bool json = false;
};

void add_options(CLI::App* cmd, Args& a) {
  AssocExperimentOptions* o = &a.o;
  cmd->add_option("--sensors", o->sensors, "number of sensors (3: the paper's positions)")->check(CLI::Range(2, 12));
  cmd->add_option("--targets", o->targets, "number of targets")->check(CLI::Range(1, 500));
  cmd->add_option("--spacing", o->spacing, "target separation d (km)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--sigma-mrad", a.sigmas, "bearing noise, mrad (one or more)")->check(CLI::PositiveNumber);
  cmd->add_option("--runs", o->runs, "Monte Carlo runs")->check(CLI::PositiveNumber);
  cmd->add_option("--cost", a.costs, "classic, kl, renyi, a comma-separated list of them, or all");
  cmd->add_option("--alpha", o->alpha, "Renyi order in (0, 1)")->check(CLI::Range(0.01, 0.99));
  cmd->add_option("--solver", a.solver, "lr (Lagrangian relaxation), exact, or both")
      ->check(CLI::IsMember({"lr", "exact", "both"}));
  cmd->add_option("--pd", o->p_detect, "detection probability")->check(CLI::Range(0.01, 1.0));
  cmd->add_option("--clutter", o->clutter, "mean false alarms per sensor per scan")->check(CLI::NonNegativeNumber);
  cmd->add_option("--layout", a.layout,
                  "more than 2 targets: grid (coplanar, spacing d) or uniform (minimum separation d)")
      ->check(CLI::IsMember({"grid", "uniform"}));
  cmd->add_flag("--target-prior", o->target_prior, "add the target-prior term to the cost");
  cmd->add_flag("--compare-exact", o->compare_exact, "also solve every scan exactly and count LR optimality");
  cmd->add_option("--max-iterations", o->max_iterations, "Lagrangian relaxation iterations")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gap", o->gap_tolerance,
                  "Lagrangian relaxation: stop when the duality gap UB - LB is below this, in cost units (nats)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", o->seed, "random seed");
  cmd->add_option("--sweep-to", a.sweep_to, "also run spacings from --spacing to this value");
  cmd->add_option("--step", a.step, "spacing step of the sweep")->check(CLI::PositiveNumber);
  cmd->add_option("--csv", a.csv, "write the per-point table as CSV, and SVG plots beside it");
  cmd->add_flag("--json", a.json, "print JSON");
}

// The costs asked for (each name checked: an unknown one throws).
std::vector<std::string> cost_names(const std::string& costs) {
  std::vector<std::string> out;
  std::stringstream ss(costs == "all" ? std::string("classic,kl,renyi") : costs);
  for (std::string c; std::getline(ss, c, ',');) {
    sextant::assoc::cost_kind_from_string(c);  // throws on an unknown name
    out.push_back(c);
  }
  return out;
}

void print_point(const Point& point) {
  const auto& p = point.options;
  const auto& r = point.result;
  std::printf(
      "sigma %g mrad, %s (%s), d %.2f: correct %.4f +- %.4f, ghosts/scan %.3f, rmse %.4f km, median %.3f ms/scan wall, "
      "%.3f CPU (build %.3f), gap mean %.2g max %.2g, tuples %.1f",
      point.sigma_mrad, point.cost.c_str(), point.solver.c_str(), p.spacing, r.correct_rate, r.correct_rate_stderr,
      r.ghosts_per_scan, r.position_rmse, r.median_ms, r.median_cpu_ms, r.build_median_ms, r.gap_mean, r.gap_max,
      r.tuples_mean);
  if (p.compare_exact)
    std::printf(", LR optimal %lld/%lld", static_cast<long long>(r.lr_optimal),
                static_cast<long long>(r.exact_compared));
  if (p.compare_exact || p.exact)
    std::printf(", %lld scan%s not proven optimal within the budget%s", static_cast<long long>(r.exact_unproven),
                r.exact_unproven == 1 ? "" : "s", p.exact ? " (not scored)" : " (not compared)");
  std::printf("\n");
  std::fflush(stdout);
}

// Every point of the sweep: per sigma, cost and solver, the spacings from --spacing to --sweep-to (printed as they
// finish unless --json).
std::vector<Point> run_points(const Args& a) {
  const std::vector<std::string> cost_list = cost_names(a.costs);
  const std::vector<std::string> solvers =
      a.solver == "both" ? std::vector<std::string>{"lr", "exact"} : std::vector<std::string>{a.solver};
  std::vector<Point> points;
  const double last = a.sweep_to >= a.o.spacing ? a.sweep_to : a.o.spacing;
  for (double sigma : a.sigmas)
    for (const auto& c : cost_list)
      for (const auto& sv : solvers)
        for (int k = 0;; ++k) {
          AssocExperimentOptions p = a.o;
          p.spacing = a.o.spacing + k * a.step;
          if (p.spacing > last + 1e-9) break;
          p.sigma = sigma * 1e-3;
          p.cost = sextant::assoc::cost_kind_from_string(c);
          p.exact = sv == "exact";
          p.compare_exact = a.o.compare_exact && !p.exact;
          points.push_back({sigma, c, sv, p, run_assoc_experiment(p)});
          if (!a.json) print_point(points.back());
        }
  return points;
}

void write_csv(const std::string& csv, const std::vector<Point>& points) {
  std::ofstream f(csv);
  f << "sigma_mrad,cost,solver,spacing,correct_rate,correct_rate_stderr,ghosts_per_scan,position_rmse,mean_ms,median_"
       "ms,"
       "median_cpu_ms,gap_mean,gap_max,tuples_mean,lr_optimal,exact_compared,exact_unproven,absolute_gap_mean\n";
  for (const auto& p : points) {
    const auto& r = p.result;
    f << p.sigma_mrad << "," << p.cost << "," << p.solver << "," << p.options.spacing << "," << r.correct_rate << ","
      << r.correct_rate_stderr << "," << r.ghosts_per_scan << "," << r.position_rmse << "," << r.mean_ms << ","
      << r.median_ms << "," << r.median_cpu_ms << "," << r.gap_mean << "," << r.gap_max << "," << r.tuples_mean << ","
      << r.lr_optimal << "," << r.exact_compared << "," << r.exact_unproven << "," << r.absolute_gap_mean << "\n";
  }
}

void print_json(const AssocExperimentOptions& o, const std::vector<Point>& points) {
  JsonWriter j;
  j.begin_object();
  j.field("sensors", o.sensors).field("targets", o.targets).field("runs", o.runs);
  j.field("pd", o.p_detect).field("clutter", o.clutter).field("target_prior", o.target_prior);
  put(j, points.front());
  j.key("points").begin_array();
  for (const auto& p : points) {
    j.begin_object();
    put(j, p);
    j.end_object();
  }
  j.end_array();
  j.end_object();
  std::fputs(j.str().c_str(), stdout);
}

void run(Args& a) {
  a.o.uniform_layout = a.layout == "uniform";
  const std::vector<Point> points = run_points(a);
  if (!a.csv.empty()) {
    write_csv(a.csv, points);
    write_plots(a.csv, points, a.sigmas);
  }
  if (a.json) print_json(a.o, points);
}

sextant::cli::RegisterCommand reg{
    "assoc-sim", [](CLI::App& app) {
      auto* cmd = app.add_subcommand(
          "assoc-sim", "Monte Carlo of multi-sensor passive association (the passive-association paper's experiment)");
      auto args = std::make_shared<Args>();
      add_options(cmd, *args);
      cmd->callback([args] { run(*args); });
    }};

}  // namespace
