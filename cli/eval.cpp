// sextant eval --gt GT.txt --est EST.txt [--format tum|kitti] [--gt-times F] [--est-times F] [--scale] [--delta D]
//              [--delta-unit s|f] [--max-difference S] [--json]
// sextant eval fleet ... (cli/eval_fleet.cpp)
#include "cli/command.hpp"
#include "cli/trajectory_evaluation.hpp"

#include <cstdio>
#include <stdexcept>

namespace {

using namespace sextant::tools;

struct Options {
  std::string gt, est, delta_unit = "s", format = "tum", gt_times, est_times;
  bool scale = false, json = false;
  double delta = 1.0, max_difference = 0.02;
};

sextant::cli::RegisterCommand reg{
    "eval", [](CLI::App& app) {
      auto* cmd =
          app.add_subcommand("eval",
                             "ATE and RPE of a trajectory against ground truth (TUM benchmark tools' semantics), "
                             "and the KITTI odometry error when the ground truth is at least 100 m long");
      auto o = std::make_shared<Options>();
      // Required unless a subcommand (`eval fleet`) runs instead: checked in the callback.
      cmd->add_option("--gt", o->gt, "ground truth")->check(CLI::ExistingFile);
      cmd->add_option("--est", o->est, "estimate")->check(CLI::ExistingFile);
      cmd->add_option("--format", o->format, "tum (stamped poses) or kitti (3x4 [R|t] per line, frame i with frame i)")
          ->check(CLI::IsMember({"tum", "kitti"}));
      cmd->add_option("--gt-times", o->gt_times, "kitti: the ground truth's times.txt (default: frame numbers)")
          ->check(CLI::ExistingFile);
      cmd->add_option("--est-times", o->est_times, "kitti: the estimate's times.txt (default: frame numbers)")
          ->check(CLI::ExistingFile);
      cmd->add_flag("--scale", o->scale, "Sim(3) alignment (monocular runs)");
      cmd->add_option("--delta", o->delta, "RPE delta")->check(CLI::PositiveNumber);
      cmd->add_option("--delta-unit", o->delta_unit, "s (seconds) or f (frames)")->check(CLI::IsMember({"s", "f"}));
      cmd->add_option("--max-difference", o->max_difference, "association window, seconds")->check(CLI::PositiveNumber);
      cmd->add_flag("--json", o->json, "print JSON");
      cmd->callback([o, cmd] {
        if (!cmd->get_subcommands().empty()) return;
        if (o->gt.empty() || o->est.empty()) {
          std::fprintf(stderr, "sextant eval: --gt and --est are required\n");
          throw CLI::RuntimeError(2);
        }
        std::vector<StampedPose> gt, est;
        try {
          if (o->format == "kitti") {
            gt = read_kitti(o->gt, o->gt_times);
            est = read_kitti(o->est, o->est_times);
          } else {
            if (!o->gt_times.empty() || !o->est_times.empty())
              throw std::runtime_error(
                  "--gt-times and --est-times are for --format kitti (TUM files carry their stamps)");
            gt = read_tum(o->gt);
            est = read_tum(o->est);
          }
        } catch (const std::exception& e) {
          std::fprintf(stderr, "sextant eval: %s\n", e.what());
          throw CLI::RuntimeError(2);
        }
        const EvaluationOptions opts{
            o->scale, o->delta, o->delta_unit == "f" ? DeltaUnit::kFrames : DeltaUnit::kSeconds, o->max_difference};
        Evaluation e;
        try {
          e = evaluate_trajectory(gt, est, opts);
        } catch (const std::exception& ex) {
          std::fprintf(stderr, "sextant eval: %s\n", ex.what());
          throw CLI::RuntimeError(1);
        }
        const AteResult& ate = e.ate;
        const bool have_rpe = e.rpe.has_value();
        const RpeResult rpe = e.rpe.value_or(RpeResult{});
        if (o->json) {
          std::fputs(e.summary(opts).json().c_str(), stdout);
        } else {
          std::printf(
              "ATE (%s): rmse %.6f m, mean %.6f, median %.6f, std %.6f, min %.6f, max %.6f over %zu of %zu poses%s\n",
              o->scale ? "Sim(3)" : "SE(3)", ate.error.rmse, ate.error.mean, ate.error.median, ate.error.std,
              ate.error.min, ate.error.max, ate.matched, est.size(),
              o->scale ? (", scale " + std::to_string(ate.scale)).c_str() : "");
          if (have_rpe)
            std::printf(
                "RPE (delta %g %s): translation rmse %.6f m, mean %.6f; rotation rmse %.4f deg, mean %.4f; %zu pairs\n",
                o->delta, o->delta_unit.c_str(), rpe.translation.rmse, rpe.translation.mean, rpe.rotation_deg.rmse,
                rpe.rotation_deg.mean, rpe.pairs);
          else
            std::printf("RPE: no pose pair with ground truth at both ends\n");
          if (e.kitti)
            std::printf("KITTI: translation %.4f %%, rotation %.6f deg/m over %zu segments of 100-800 m\n",
                        e.kitti->translation_percent, e.kitti->rotation_deg_per_m, e.kitti->segments.size());
        }
      });
    }};

}  // namespace
