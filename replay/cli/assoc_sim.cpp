// sextant assoc-sim --sensors N --targets N --spacing D --sigma-mrad S --runs R --cost classic|kl|renyi
//                   --solver lr|exact [--pd P] [--clutter C] [--seed K] [--json] [--sweep-to D --step S --csv F]
#include "replay/assoc_experiment.hpp"
#include "replay/cli/command.hpp"
#include "replay/json_writer.hpp"

#include <cstdio>
#include <fstream>

namespace {

using namespace sextant::replay;

void put(JsonWriter& j, const AssocExperimentOptions& o, const AssocExperimentResult& r) {
  j.field("spacing", o.spacing).field("correct_rate", r.correct_rate).field("correct_rate_stderr", r.correct_rate_stderr);
  j.field("observable_targets", r.observable_targets).field("ghosts_per_scan", r.ghosts_per_scan);
  j.field("position_rmse", r.position_rmse).field("mean_ms", r.mean_ms).field("gap_mean", r.gap_mean);
  j.field("tuples_mean", r.tuples_mean);
}

sextant::cli::RegisterCommand reg{"assoc-sim", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("assoc-sim", "Monte Carlo of multi-sensor passive association (source C's experiment)");
  auto o = std::make_shared<AssocExperimentOptions>();
  auto sigma_mrad = std::make_shared<double>(5), sweep_to = std::make_shared<double>(-1), step = std::make_shared<double>(0.1);
  auto cost = std::make_shared<std::string>("classic"), solver = std::make_shared<std::string>("lr"), csv = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("--sensors", o->sensors, "number of sensors (3: the paper's positions)")->check(CLI::Range(2, 12));
  cmd->add_option("--targets", o->targets, "number of targets")->check(CLI::Range(1, 500));
  cmd->add_option("--spacing", o->spacing, "target separation d (km)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--sigma-mrad", *sigma_mrad, "bearing noise, mrad")->check(CLI::PositiveNumber);
  cmd->add_option("--runs", o->runs, "Monte Carlo runs")->check(CLI::PositiveNumber);
  cmd->add_option("--cost", *cost, "classic, kl or renyi")->check(CLI::IsMember({"classic", "kl", "renyi"}));
  cmd->add_option("--alpha", o->alpha, "Renyi order in (0, 1)")->check(CLI::Range(0.01, 0.99));
  cmd->add_option("--solver", *solver, "lr (Lagrangian relaxation) or exact")->check(CLI::IsMember({"lr", "exact"}));
  cmd->add_option("--pd", o->p_detect, "detection probability")->check(CLI::Range(0.01, 1.0));
  cmd->add_option("--clutter", o->clutter, "mean false alarms per sensor per scan")->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", o->seed, "random seed");
  cmd->add_option("--sweep-to", *sweep_to, "also run spacings from --spacing to this value");
  cmd->add_option("--step", *step, "spacing step of the sweep")->check(CLI::PositiveNumber);
  cmd->add_option("--csv", *csv, "write the per-point table as CSV");
  cmd->add_flag("--json", *json, "print JSON");
  cmd->callback([=] {
    o->sigma = *sigma_mrad * 1e-3;
    o->cost = sextant::assoc::cost_kind_from_string(*cost);
    o->exact = *solver == "exact";
    std::vector<std::pair<AssocExperimentOptions, AssocExperimentResult>> points;
    const double last = *sweep_to >= o->spacing ? *sweep_to : o->spacing;
    for (int k = 0;; ++k) {
      AssocExperimentOptions p = *o;
      p.spacing = o->spacing + k * *step;
      if (p.spacing > last + 1e-9) break;
      points.push_back({p, run_assoc_experiment(p)});
    }
    if (!csv->empty()) {
      std::ofstream f(*csv);
      f << "spacing,correct_rate,correct_rate_stderr,ghosts_per_scan,position_rmse,mean_ms,gap_mean\n";
      for (const auto& [p, r] : points)
        f << p.spacing << "," << r.correct_rate << "," << r.correct_rate_stderr << "," << r.ghosts_per_scan << ","
          << r.position_rmse << "," << r.mean_ms << "," << r.gap_mean << "\n";
    }
    if (*json) {
      JsonWriter j;
      j.begin_object();
      j.field("sensors", o->sensors).field("targets", o->targets).field("sigma_mrad", *sigma_mrad).field("runs", o->runs);
      j.field("cost", *cost).field("solver", *solver).field("pd", o->p_detect).field("clutter", o->clutter);
      put(j, points.front().first, points.front().second);
      j.key("points").begin_array();
      for (const auto& [p, r] : points) {
        j.begin_object();
        put(j, p, r);
        j.end_object();
      }
      j.end_array();
      j.end_object();
      std::fputs(j.str().c_str(), stdout);
    } else {
      for (const auto& [p, r] : points)
        std::printf("d %.2f: correct %.4f +- %.4f, ghosts/scan %.3f, rmse %.4f km, %.3f ms/scan, gap %.2g, tuples %.1f\n",
                    p.spacing, r.correct_rate, r.correct_rate_stderr, r.ghosts_per_scan, r.position_rmse, r.mean_ms,
                    r.gap_mean, r.tuples_mean);
    }
  });
}};

}  // namespace
