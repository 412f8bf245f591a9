// sextant optimize IN.g2o [-o OUT.g2o] [--solver gn|lm] [--init auto|file|odometry|chordal|sgd]
//                         [--robust none|huber|cauchy|dcs] [--information reject|repair|diagonal] [--max-iters N]
//                         [--incremental] [--json]
#include "estimators/graph/feed_in_order.hpp"
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/initialization.hpp"
#include "estimators/graph/optimizer.hpp"
#include "replay/cli/command.hpp"
#include "replay/json_writer.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <numeric>

namespace {

using namespace sextant;

struct Options {
  std::string input, output, solver = "gn", init = "auto", robust = "none", ordering = "block-amd", information = "reject";
  int max_iters = 100;
  double kernel_width = 1.0;
  double tolerance = 1e-6;
  bool json = false;
  bool incremental = false;
  double relin_translation = 0.1, relin_rotation = 0.1;
  int relin_skip = 1;
};


double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(std::min<double>(static_cast<double>(v.size() - 1), std::ceil(q * static_cast<double>(v.size())) - 1))];
}

// --incremental: the file's factors fed in order to the incremental smoother (feed_in_order.hpp), then a batch
// Gauss-Newton solve of the same graph from the same start for the final chi2 ratio.
void run_incremental(graph::G2oGraph& g, const Options& o) {
  graph::IncrementalOptions io;
  io.kernel = graph::robust_kernel_from_name(o.robust);
  io.kernel_width = o.kernel_width;
  io.relinearize_translation = o.relin_translation;
  io.relinearize_rotation = o.relin_rotation;
  io.relinearize_skip = o.relin_skip;
  graph::IncrementalSmoother smoother(io);
  const auto t0 = std::chrono::steady_clock::now();
  graph::FeedResult r = graph::feed_in_order(g.graph, smoother);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double peak_mb = static_cast<double>(ru.ru_maxrss) / 1024.0;  // before the batch reference runs
  const double initial_chi2 = r.start.chi2();
  const double final_chi2 = smoother.chi2();
  graph::OptimizerOptions bo;
  bo.kernel = io.kernel;
  bo.kernel_width = io.kernel_width;
  bo.max_iterations = o.max_iters;
  bo.relative_tolerance = o.tolerance;
  const auto batch = graph::optimize(r.start, bo);
  const double mean = r.step_ms.empty() ? 0 : std::accumulate(r.step_ms.begin(), r.step_ms.end(), 0.0) / static_cast<double>(r.step_ms.size());
  const double ratio = batch.usable() && batch.final_chi2 > 0 ? final_chi2 / batch.final_chi2 : 0;
  if (!o.output.empty()) graph::write_g2o(o.output, smoother.graph());
  if (o.json) {
    replay::JsonWriter j;
    j.begin_object();
    j.field("vertices", smoother.graph().variables().size()).field("edges", smoother.graph().factors().size());
    j.field("dimension", g.dimension).field("iterations", r.step_ms.size());
    j.field("initial_chi2", initial_chi2).field("final_chi2", final_chi2);
    j.field("solve_seconds", seconds).field("converged", r.ok);
    j.field("step_ms_mean", mean).field("step_ms_p50", percentile(r.step_ms, 0.5));
    j.field("step_ms_p99", percentile(r.step_ms, 0.99)).field("step_ms_max", percentile(r.step_ms, 1.0));
    j.field("final_chi2_batch_ratio", ratio).field("batch_final_chi2", batch.final_chi2);
    j.field("updates", r.step_ms.size()).field("rebuilds", r.rebuilds).field("relinearize_skip", o.relin_skip).field("relinearized_factors", r.relinearized_factors);
    j.field("factor_nonzeros", smoother.factor_nonzeros()).field("peak_rss_mb", peak_mb);
    j.field("robust", o.robust);
    if (!r.ok) j.field("termination", r.message);
    j.end_object();
    std::fputs(j.str().c_str(), stdout);
  } else {
    std::printf("%s: %zu vertices, %zu edges (%dD); incremental, %zu updates: step mean %.3f ms, p50 %.3f, p99 %.3f, "
                "max %.3f; chi2 %.6f (batch from the same start %.6f, ratio %.6f); %d rebuilds; %.3f s\n",
                o.input.c_str(), smoother.graph().variables().size(), smoother.graph().factors().size(), g.dimension,
                r.step_ms.size(), mean, percentile(r.step_ms, 0.5), percentile(r.step_ms, 0.99),
                percentile(r.step_ms, 1.0), final_chi2, batch.final_chi2, ratio, r.rebuilds, seconds);
  }
  if (!r.ok) {
    std::fprintf(stderr, "sextant optimize: %s\n", r.message.c_str());
    throw CLI::RuntimeError(1);
  }
}

sextant::cli::RegisterCommand reg{"optimize", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("optimize", "optimize a g2o pose graph (Gauss-Newton or Levenberg-Marquardt on CHOLMOD)");
  auto o = std::make_shared<Options>();
  cmd->add_option("input", o->input, "g2o file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->output, "write the optimized graph (g2o format)");
  cmd->add_option("--solver", o->solver, "gn or lm")->check(CLI::IsMember({"gn", "lm"}));
  cmd->add_option("--init", o->init, "initial estimate: auto (the default: chordal when its chi2 is below the file's, else the "
                  "file's), file (the file's vertices), odometry (spanning tree), chordal (rotation relaxation), "
                  "sgd (Olson's SGD from odometry, planar graphs)")
      ->check(CLI::IsMember({"auto", "file", "odometry", "chordal", "sgd"}));
  cmd->add_option("--information", o->information, "information matrices that are not positive definite: reject (the default: "
                  "an error listing them), repair (nearest positive definite, eigenvalues floored at 1e-6 of the largest) or "
                  "diagonal (their diagonal, floored the same way)")
      ->check(CLI::IsMember({"reject", "repair", "diagonal"}));
  cmd->add_option("--robust", o->robust, "robust kernel")->check(CLI::IsMember({"none", "huber", "cauchy", "dcs"}));
  cmd->add_option("--kernel-width", o->kernel_width, "Huber/Cauchy delta or DCS phi")->check(CLI::PositiveNumber);
  cmd->add_option("--max-iters", o->max_iters, "maximum iterations")->check(CLI::PositiveNumber);
  cmd->add_option("--tolerance", o->tolerance, "stop when chi2 decreases by less than this fraction")->check(CLI::PositiveNumber);
  cmd->add_option("--ordering", o->ordering, "fill-reducing ordering")->check(CLI::IsMember({"block-amd", "amd", "colamd", "metis", "auto"}));
  cmd->add_flag("--json", o->json, "print a JSON summary");
  cmd->add_flag("--incremental", o->incremental, "feed the edges in file order to the incremental smoother, one update per new pose; "
                "reports per-step latency and the final chi2 against a batch solve from the same start");
  cmd->add_option("--relin-translation", o->relin_translation, "incremental: relinearize a variable whose step exceeds this (m)")->check(CLI::PositiveNumber);
  cmd->add_option("--relin-rotation", o->relin_rotation, "incremental: relinearize a variable whose step exceeds this (rad)")->check(CLI::PositiveNumber);
  cmd->add_option("--relin-skip", o->relin_skip, "incremental: look for variables to relinearize every this many updates "
                  "(iSAM2's relinearizeSkip, 10 by its default; 1, the default here, keeps every update's estimate at the "
                  "batch optimum)")->check(CLI::PositiveNumber);
  cmd->callback([o] {
    graph::G2oGraph g;
    graph::G2oReadOptions read_options;
    read_options.information = o->information == "repair"     ? graph::InformationPolicy::kRepair
                               : o->information == "diagonal" ? graph::InformationPolicy::kDiagonal
                                                              : graph::InformationPolicy::kReject;
    try {
      g = graph::read_g2o(o->input, read_options);
    } catch (const graph::IndefiniteInformationError& e) {
      std::fprintf(stderr, "sextant optimize: %s\n  (--information repair uses the nearest positive definite matrices, "
                   "--information diagonal their diagonals)\n", e.what());
      throw CLI::RuntimeError(2);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "sextant optimize: %s\n", e.what());
      throw CLI::RuntimeError(2);
    }
    if (g.repaired_information > 0 && !o->json)
      std::printf("%s: %d information matrices were not positive definite; used %s\n", o->input.c_str(), g.repaired_information,
                  o->information == "repair" ? "the nearest positive definite ones" : "their diagonals");
    if (o->incremental) {
      if (o->init == "auto") o->init = "file";  // the default: the incremental smoother starts each pose from its edges
      if (o->init != "file" || o->solver != "gn") {
        std::fprintf(stderr, "sextant optimize: --incremental initializes each pose from its first edge; --init and --solver do not apply\n");
        throw CLI::RuntimeError(2);
      }
      run_incremental(g, *o);
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    std::string init_used = o->init;
    if (o->init == "auto") {
      init_used = graph::initialize_auto(g.graph) ? "chordal" : "file";
    } else if (o->init == "odometry") {
      graph::initialize_by_odometry(g.graph);
    } else if (o->init == "chordal" || o->init == "sgd") {
      if (o->init == "sgd") graph::initialize_by_odometry(g.graph);
      if (auto why = o->init == "sgd" ? graph::initialize_sgd(g.graph) : graph::initialize_chordal(g.graph); !why.empty()) {
        std::fprintf(stderr, "sextant optimize: %s\n", why.c_str());
        throw CLI::RuntimeError(1);
      }
    }
    graph::OptimizerOptions opt;
    opt.method = o->solver == "lm" ? graph::Method::kLevenbergMarquardt : graph::Method::kGaussNewton;
    opt.max_iterations = o->max_iters;
    opt.relative_tolerance = o->tolerance;
    opt.kernel = graph::robust_kernel_from_name(o->robust);
    opt.kernel_width = o->kernel_width;
    opt.ordering = o->ordering == "block-amd" ? graph::Ordering::kBlockAmd
                   : o->ordering == "colamd" ? graph::Ordering::kColamd
                   : o->ordering == "metis" ? graph::Ordering::kMetis
                   : o->ordering == "auto" ? graph::Ordering::kAuto : graph::Ordering::kAmd;
    const auto s = graph::optimize(g.graph, opt);
    const double solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!o->output.empty()) graph::write_g2o(o->output, g.graph);
    if (o->json) {
      replay::JsonWriter j;
      j.begin_object();
      j.field("vertices", g.graph.variables().size()).field("edges", g.graph.factors().size());
      j.field("dimension", g.dimension).field("iterations", s.iterations);
      j.field("initial_chi2", s.initial_chi2).field("final_chi2", s.final_chi2);
      j.field("solve_seconds", solve_seconds).field("converged", s.converged());
      j.field("solver", o->solver).field("init", o->init).field("init_used", init_used).field("robust", o->robust);
      j.field("repaired_information", g.repaired_information);
      j.field("termination", s.message);
      j.field("linearize_seconds", s.linearize_seconds).field("factorize_seconds", s.factorize_seconds);
      j.field("linear_solve_seconds", s.solve_seconds);
      if (o->robust != "none") j.field("final_robust_cost", s.final_cost);
      j.end_object();
      std::fputs(j.str().c_str(), stdout);
    } else {
      std::printf("%s: %zu vertices, %zu edges (%dD); %s from %s: chi2 %.6f -> %.6f in %d iterations, %.3f s (%s)\n",
                  o->input.c_str(), g.graph.variables().size(), g.graph.factors().size(), g.dimension,
                  o->solver.c_str(), (o->init == "auto" ? "auto: " + init_used : init_used).c_str(), s.initial_chi2, s.final_chi2, s.iterations, solve_seconds,
                  s.message.c_str());
    }
    if (!s.usable()) {
      std::fprintf(stderr, "sextant optimize: %s\n", s.message.c_str());
      throw CLI::RuntimeError(1);
    }
  });
}};

}  // namespace
