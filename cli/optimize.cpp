// sextant optimize IN.g2o [-o OUT.g2o] [--solver gn|lm] [--init auto|file|odometry|chordal|sgd]
//                         [--robust none|huber|cauchy|dcs] [--information reject|repair|diagonal] [--max-iters N]
//                         [--incremental [--step-trace CSV [--step-reference N]]] [--json]
#include "cli/command.hpp"
#include "cli/graph_optimization.hpp"

#include <cstdio>

namespace {

using namespace sextant;
using Options = tools::GraphOptimizationOptions;

double number(const tools::Summary& s, const std::string& key) {
  for (const auto& [k, v] : s.entries())
    if (k == key) {
      if (const double* d = std::get_if<double>(&v)) return *d;
      if (const int64_t* i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
    }
  return 0;
}

std::string text(const tools::Summary& s, const std::string& key) {
  for (const auto& [k, v] : s.entries())
    if (k == key)
      if (const std::string* t = std::get_if<std::string>(&v)) return *t;
  return "";
}

// The command's arguments; the kinds' spellings are parsed once by the callback (each kind's spelling table sits
// beside its enum).
struct Args {
  Options o;
  std::string solver = "gn", init = "auto", robust = "none", ordering = "block-amd", information = "reject";
  std::string input, output;
  bool json = false;
};

void add_options(CLI::App* cmd, Args& a) {
  Options* o = &a.o;
  cmd->add_option("input", a.input, "g2o file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", a.output, "write the optimized graph (g2o format)");
  cmd->add_option("--solver", a.solver, "gn or lm")->check(CLI::IsMember(tools::solver_names()));
  cmd->add_option("--init", a.init,
                  "initial estimate: auto (the default: chordal when its chi2 is below the file's, else the "
                  "file's), file (the file's vertices), odometry (spanning tree), chordal (rotation relaxation), "
                  "sgd (Olson's SGD from odometry, planar graphs)")
      ->check(CLI::IsMember(tools::initial_estimate_names()));
  cmd->add_option(
         "--information", a.information,
         "information matrices that are not positive definite: reject (the default: "
         "an error listing them), repair (nearest positive definite, eigenvalues floored at 1e-6 of the largest) or "
         "diagonal (their diagonal, floored the same way)")
      ->check(CLI::IsMember(graph::information_policy_names()));
  cmd->add_option("--robust", a.robust, "robust kernel")->check(CLI::IsMember(graph::robust_kernel_names()));
  cmd->add_option("--kernel-width", o->kernel_width, "Huber/Cauchy delta or DCS phi")->check(CLI::PositiveNumber);
  cmd->add_option("--max-iters", o->max_iters, "maximum iterations")->check(CLI::PositiveNumber);
  cmd->add_option("--tolerance", o->tolerance, "stop when chi2 decreases by less than this fraction")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ordering", a.ordering, "fill-reducing ordering")->check(CLI::IsMember(tools::ordering_names()));
  cmd->add_flag("--json", a.json, "print a JSON summary");
  cmd->add_flag("--incremental", o->incremental,
                "feed the edges in file order to the incremental smoother, one update per new pose; "
                "reports per-step latency and the final chi2 against a batch solve from the same start");
  cmd->add_option("--relin-translation", o->relin_translation,
                  "incremental: relinearize a variable whose step exceeds this (m)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--relin-rotation", o->relin_rotation,
                  "incremental: relinearize a variable whose step exceeds this (rad)")
      ->check(CLI::PositiveNumber);
  cmd->add_option(
         "--relin-skip", o->relin_skip,
         "incremental: look for variables to relinearize every this many updates "
         "(iSAM2's relinearizeSkip, 10 by its default; 1, the default here, keeps every update's estimate at the "
         "batch optimum)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--relin-heavy-every", o->relin_heavy_every,
                  "incremental: relinearize a variable whose rank updates alone exceed the work budget (3-D: a pose "
                  "on long dense paths of the factor) only every this many updates")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--step-trace", o->step_trace,
                  "incremental: write one CSV line per update (time, factors entered and relinearized, rebuilds, "
                  "nnz of L, chi2 of the online estimate) to this file");
  cmd->add_option("--step-reference", o->step_reference,
                  "incremental, with --step-trace: also solve the factors so far as a batch every this many updates "
                  "(and at the last) and write that optimum's chi2 beside the online one")
      ->check(CLI::NonNegativeNumber);
}

// The graph, its bad information matrices refused (exit 2, with the options that would repair them) or repaired
// as asked (said unless --json).
graph::G2oGraph read_graph(const Args& a) {
  graph::G2oGraph g;
  graph::G2oReadOptions read_options;
  read_options.information = graph::information_policy_from_name(a.information);
  try {
    g = graph::read_g2o(a.input, read_options);
  } catch (const graph::IndefiniteInformationError& e) {
    std::fprintf(stderr,
                 "sextant optimize: %s\n  (--information repair uses the nearest positive definite matrices, "
                 "--information diagonal their diagonals)\n",
                 e.what());
    throw CLI::RuntimeError(2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sextant optimize: %s\n", e.what());
    throw CLI::RuntimeError(2);
  }
  if (g.repaired_information > 0 && !a.json)
    std::printf("%s: %d information matrices were not positive definite; used %s\n", a.input.c_str(),
                g.repaired_information,
                read_options.information == graph::InformationPolicy::kRepair ? "the nearest positive definite ones"
                                                                              : "their diagonals");
  return g;
}

// The summary: JSON, or one line (the incremental run's latencies, or the batch run's chi2 and iterations).
void print_summary(const Args& a, const tools::Summary& s) {
  if (a.json) {
    std::fputs(s.json().c_str(), stdout);
  } else if (a.o.incremental) {
    std::printf(
        "%s: %.0f vertices, %.0f edges (%.0fD); incremental, %.0f updates: step mean %.3f ms, p50 %.3f, "
        "p99 %.3f, max %.3f; chi2 %.6f (batch from the same start %.6f, ratio %.6f); %.0f rebuilds; %.3f s\n",
        a.input.c_str(), number(s, "vertices"), number(s, "edges"), number(s, "dimension"), number(s, "updates"),
        number(s, "step_ms_mean"), number(s, "step_ms_p50"), number(s, "step_ms_p99"), number(s, "step_ms_max"),
        number(s, "final_chi2"), number(s, "batch_final_chi2"), number(s, "final_chi2_batch_ratio"),
        number(s, "rebuilds"), number(s, "solve_seconds"));
  } else {
    std::printf(
        "%s: %.0f vertices, %.0f edges (%.0fD); %s from %s: chi2 %.6f -> %.6f in %.0f iterations, %.3f s (%s)\n",
        a.input.c_str(), number(s, "vertices"), number(s, "edges"), number(s, "dimension"), a.solver.c_str(),
        (a.o.init == tools::InitialEstimate::kAuto ? "auto: " + text(s, "init_used") : text(s, "init_used")).c_str(),
        number(s, "initial_chi2"), number(s, "final_chi2"), number(s, "iterations"), number(s, "solve_seconds"),
        text(s, "termination").c_str());
  }
}

void run(Args& a) {
  a.o.solver = tools::solver_from_name(a.solver);
  a.o.init = tools::initial_estimate_from_name(a.init);
  a.o.robust = graph::robust_kernel_from_name(a.robust);
  a.o.ordering = tools::ordering_from_name(a.ordering);
  graph::G2oGraph g = read_graph(a);
  tools::GraphOptimizationResult r;
  try {
    r = tools::optimize_graph(g, a.o, a.output);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "sextant optimize: %s\n", e.what());
    throw CLI::RuntimeError(2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sextant optimize: %s\n", e.what());
    throw CLI::RuntimeError(1);
  }
  print_summary(a, r.summary);
  if (!r.ok) {
    std::fprintf(stderr, "sextant optimize: %s\n", r.message.c_str());
    throw CLI::RuntimeError(1);
  }
}

sextant::cli::RegisterCommand reg{
    "optimize", [](CLI::App& app) {
      auto* cmd =
          app.add_subcommand("optimize", "optimize a g2o pose graph (Gauss-Newton or Levenberg-Marquardt on CHOLMOD)");
      auto args = std::make_shared<Args>();
      add_options(cmd, *args);
      cmd->callback([args] { run(*args); });
    }};

}  // namespace
