// sextant optimize IN.g2o [-o OUT.g2o] [--solver gn|lm] [--init file|odometry|chordal] [--robust none|huber|cauchy|dcs]
//                         [--max-iters N] [--json]
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/initialization.hpp"
#include "estimators/graph/optimizer.hpp"
#include "replay/cli/command.hpp"
#include "replay/json_writer.hpp"

#include <chrono>
#include <cstdio>

namespace {

using namespace sextant;

struct Options {
  std::string input, output, solver = "gn", init = "file", robust = "none", ordering = "block-amd";
  int max_iters = 100;
  double kernel_width = 1.0;
  double tolerance = 1e-6;
  bool json = false;
};

sextant::cli::RegisterCommand reg{"optimize", [](CLI::App& app) {
  auto* cmd = app.add_subcommand("optimize", "optimize a g2o pose graph (Gauss-Newton or Levenberg-Marquardt on CHOLMOD)");
  auto o = std::make_shared<Options>();
  cmd->add_option("input", o->input, "g2o file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o->output, "write the optimized graph (g2o format)");
  cmd->add_option("--solver", o->solver, "gn or lm")->check(CLI::IsMember({"gn", "lm"}));
  cmd->add_option("--init", o->init, "initial estimate: file (the file's vertices), odometry (spanning tree), chordal (rotation relaxation), "
                  "sgd (Olson's SGD from odometry, planar graphs)")
      ->check(CLI::IsMember({"file", "odometry", "chordal", "sgd"}));
  cmd->add_option("--robust", o->robust, "robust kernel")->check(CLI::IsMember({"none", "huber", "cauchy", "dcs"}));
  cmd->add_option("--kernel-width", o->kernel_width, "Huber/Cauchy delta or DCS phi")->check(CLI::PositiveNumber);
  cmd->add_option("--max-iters", o->max_iters, "maximum iterations")->check(CLI::PositiveNumber);
  cmd->add_option("--tolerance", o->tolerance, "stop when chi2 decreases by less than this fraction")->check(CLI::PositiveNumber);
  cmd->add_option("--ordering", o->ordering, "fill-reducing ordering")->check(CLI::IsMember({"block-amd", "amd", "colamd", "metis", "auto"}));
  cmd->add_flag("--json", o->json, "print a JSON summary");
  cmd->callback([o] {
    graph::G2oGraph g;
    try {
      g = graph::read_g2o(o->input);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "sextant optimize: %s\n", e.what());
      throw CLI::RuntimeError(2);
    }
    const auto t0 = std::chrono::steady_clock::now();
    if (o->init == "odometry") {
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
    opt.kernel = o->robust == "huber" ? graph::RobustKernel::kHuber
                 : o->robust == "cauchy" ? graph::RobustKernel::kCauchy
                 : o->robust == "dcs" ? graph::RobustKernel::kDcs : graph::RobustKernel::kNone;
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
      j.field("solver", o->solver).field("init", o->init).field("robust", o->robust);
      j.field("termination", s.message);
      j.field("linearize_seconds", s.linearize_seconds).field("factorize_seconds", s.factorize_seconds);
      j.field("linear_solve_seconds", s.solve_seconds);
      if (o->robust != "none") j.field("final_robust_cost", s.final_cost);
      j.end_object();
      std::fputs(j.str().c_str(), stdout);
    } else {
      std::printf("%s: %zu vertices, %zu edges (%dD); %s from %s: chi2 %.6f -> %.6f in %d iterations, %.3f s (%s)\n",
                  o->input.c_str(), g.graph.variables().size(), g.graph.factors().size(), g.dimension,
                  o->solver.c_str(), o->init.c_str(), s.initial_chi2, s.final_chi2, s.iterations, solve_seconds,
                  s.message.c_str());
    }
    if (!s.usable()) {
      std::fprintf(stderr, "sextant optimize: %s\n", s.message.c_str());
      throw CLI::RuntimeError(1);
    }
  });
}};

}  // namespace
