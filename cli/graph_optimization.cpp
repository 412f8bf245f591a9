#include "cli/graph_optimization.hpp"

#include "estimators/graph/feed_in_order.hpp"
#include "estimators/graph/initialization.hpp"
#include "estimators/graph/optimizer.hpp"
#include "estimators/kind_names.hpp"
#include "daemon/runtime/nearest_rank_percentile.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>

namespace sextant::tools {
namespace {

constexpr std::pair<graph::Method, const char*> kSolvers[] = {{graph::Method::kGaussNewton, "gn"},
                                                              {graph::Method::kLevenbergMarquardt, "lm"}};
constexpr std::pair<InitialEstimate, const char*> kInits[] = {{InitialEstimate::kAuto, "auto"},
                                                              {InitialEstimate::kFile, "file"},
                                                              {InitialEstimate::kOdometry, "odometry"},
                                                              {InitialEstimate::kChordal, "chordal"},
                                                              {InitialEstimate::kSgd, "sgd"}};
constexpr std::pair<graph::Ordering, const char*> kOrderings[] = {{graph::Ordering::kBlockAmd, "block-amd"},
                                                                  {graph::Ordering::kAmd, "amd"},
                                                                  {graph::Ordering::kColamd, "colamd"},
                                                                  {graph::Ordering::kMetis, "metis"},
                                                                  {graph::Ordering::kAuto, "auto"}};

// One line per update: its time, what entered, what was relinearized, whether it rebuilt (or installed a spread
// reordering) and whether a spread reordering is under way after it, nnz(L): where a slow step's time went; the
// chi2 of the online estimate after it, and at sampled updates the batch optimum's of the same factors (empty
// elsewhere): how far the online answer is from the best one.
void write_step_trace(const std::string& path, const graph::FeedResult& r) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw std::runtime_error("cannot write the step trace " + path);
  std::fprintf(f,
               "update,ms,new_factors,relinearized_variables,relinearized_factors,rebuilt,reordering,solves,"
               "factor_nonzeros,chi2,batch_chi2\n");
  for (size_t k = 0; k < r.steps.size(); ++k) {
    const graph::FeedStep& s = r.steps[k];
    std::fprintf(f, "%zu,%.4f,%d,%d,%d,%d,%d,%d,%zu,%.10g,", k + 1, r.step_ms[k], s.status.new_factors,
                 s.status.relinearized_variables, s.status.relinearized_factors, s.status.rebuilt ? 1 : 0,
                 s.reordering ? 1 : 0, s.status.solves, s.factor_nonzeros, s.chi2);
    if (std::isnan(s.batch_chi2))
      std::fprintf(f, "\n");
    else
      std::fprintf(f, "%.10g\n", s.batch_chi2);
  }
  if (std::fclose(f) != 0) throw std::runtime_error("cannot write the step trace " + path);
}

// The file's factors fed in order to the incremental smoother (feed_in_order.hpp), then a batch Gauss-Newton solve
// of the same graph from the same start for the final chi2 ratio.
GraphOptimizationResult run_incremental(const graph::G2oGraph& g, const GraphOptimizationOptions& o,
                                        const std::string& output) {
  graph::IncrementalOptions io;
  io.kernel = o.robust;
  io.kernel_width = o.kernel_width;
  io.relinearize_translation = o.relin_translation;
  io.relinearize_rotation = o.relin_rotation;
  io.relinearize_skip = o.relin_skip;
  io.heavy_relinearize_every = o.relin_heavy_every;
  graph::IncrementalSmoother smoother(io);
  const auto t0 = std::chrono::steady_clock::now();
  graph::FeedOptions feed;
  feed.chi2 = !o.step_trace.empty();
  feed.reference_every = o.step_trace.empty() ? 0 : o.step_reference;
  graph::FeedResult r = graph::feed_in_order(g.graph, smoother, feed);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.step_trace.empty()) write_step_trace(o.step_trace, r);
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
  const double mean = r.step_ms.empty() ? 0
                                        : std::accumulate(r.step_ms.begin(), r.step_ms.end(), 0.0) /
                                              static_cast<double>(r.step_ms.size());
  const double ratio = batch.usable() && batch.final_chi2 > 0 ? final_chi2 / batch.final_chi2 : 0;
  if (!output.empty()) graph::write_g2o(output, smoother.graph());

  GraphOptimizationResult res;
  auto& s = res.summary;
  s.add("vertices", smoother.graph().variables().size()).add("edges", smoother.graph().factors().size());
  s.add("dimension", g.dimension).add("iterations", r.step_ms.size());
  s.add("initial_chi2", initial_chi2).add("final_chi2", final_chi2);
  s.add("solve_seconds", seconds).add("converged", r.ok);
  s.add("step_ms_mean", mean).add("step_ms_p50", runtime::nearest_rank_percentile_of(r.step_ms, 0.5));
  s.add("step_ms_p99", runtime::nearest_rank_percentile_of(r.step_ms, 0.99))
      .add("step_ms_max", runtime::nearest_rank_percentile_of(r.step_ms, 1.0));
  s.add("final_chi2_batch_ratio", ratio).add("batch_final_chi2", batch.final_chi2);
  s.add("updates", r.step_ms.size()).add("rebuilds", r.rebuilds).add("relinearize_skip", o.relin_skip);
  s.add("heavy_relinearize_every", o.relin_heavy_every);
  s.add("relinearized_factors", r.relinearized_factors);
  s.add("factor_nonzeros", static_cast<int64_t>(smoother.factor_nonzeros())).add("peak_rss_mb", peak_mb);
  s.add("robust", graph::robust_kernel_name(o.robust));
  if (!r.ok) s.add("termination", r.message);
  res.ok = r.ok;
  res.message = r.ok ? "" : r.message;
  res.variables = smoother.graph().variables();
  return res;
}

}  // namespace

graph::Method solver_from_name(const std::string& name) { return kind_from_name(kSolvers, name, "solver"); }
InitialEstimate initial_estimate_from_name(const std::string& name) { return kind_from_name(kInits, name, "init"); }
graph::Ordering ordering_from_name(const std::string& name) { return kind_from_name(kOrderings, name, "ordering"); }
const char* name_of(graph::Method solver) { return kind_name(kSolvers, solver); }
const char* name_of(InitialEstimate init) { return kind_name(kInits, init); }
const char* name_of(graph::Ordering ordering) { return kind_name(kOrderings, ordering); }
std::vector<std::string> solver_names() { return kind_names(kSolvers); }
std::vector<std::string> initial_estimate_names() { return kind_names(kInits); }
std::vector<std::string> ordering_names() { return kind_names(kOrderings); }

GraphOptimizationResult optimize_graph(graph::G2oGraph& g, const GraphOptimizationOptions& o,
                                       const std::string& output) {
  if (o.max_iters < 1) throw std::invalid_argument("max_iters must be at least 1");
  if (!(o.kernel_width > 0) || !(o.tolerance > 0))
    throw std::invalid_argument("kernel_width and tolerance must be > 0");
  if (o.incremental) {
    // auto, the default, means the file here: the incremental smoother starts each pose from its edges.
    const bool file_start = o.init == InitialEstimate::kFile || o.init == InitialEstimate::kAuto;
    if (!file_start || o.solver != graph::Method::kGaussNewton)
      throw std::invalid_argument(
          "incremental initializes each pose from its first edge; init and solver do not apply");
    if (!(o.relin_translation > 0) || !(o.relin_rotation > 0) || o.relin_skip < 1 || o.relin_heavy_every < 1)
      throw std::invalid_argument(
          "relinearization thresholds must be > 0 and relin_skip and relin_heavy_every at least 1");
    return run_incremental(g, o, output);
  }

  const auto t0 = std::chrono::steady_clock::now();
  InitialEstimate init_used = o.init;
  if (o.init == InitialEstimate::kAuto) {
    init_used = graph::initialize_auto(g.graph) ? InitialEstimate::kChordal : InitialEstimate::kFile;
  } else if (o.init == InitialEstimate::kOdometry) {
    graph::initialize_by_odometry(g.graph);
  } else if (o.init == InitialEstimate::kChordal || o.init == InitialEstimate::kSgd) {
    const bool sgd = o.init == InitialEstimate::kSgd;
    if (sgd) graph::initialize_by_odometry(g.graph);
    if (auto why = sgd ? graph::initialize_sgd(g.graph) : graph::initialize_chordal(g.graph); !why.empty())
      throw std::runtime_error(why);
  }
  const double init_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  graph::OptimizerOptions opt;
  opt.method = o.solver;
  opt.max_iterations = o.max_iters;
  opt.relative_tolerance = o.tolerance;
  opt.kernel = o.robust;
  opt.kernel_width = o.kernel_width;
  opt.ordering = o.ordering;
  const auto st = graph::optimize(g.graph, opt);
  const double solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!output.empty()) graph::write_g2o(output, g.graph);

  GraphOptimizationResult res;
  auto& s = res.summary;
  s.add("vertices", g.graph.variables().size()).add("edges", g.graph.factors().size());
  s.add("dimension", g.dimension).add("iterations", st.iterations);
  s.add("initial_chi2", st.initial_chi2).add("final_chi2", st.final_chi2);
  s.add("solve_seconds", solve_seconds).add("converged", st.converged());
  s.add("solver", name_of(o.solver)).add("init", name_of(o.init)).add("init_used", name_of(init_used));
  s.add("robust", graph::robust_kernel_name(o.robust));
  s.add("repaired_information", g.repaired_information);
  s.add("termination", st.message);
  s.add("linearize_seconds", st.linearize_seconds).add("factorize_seconds", st.factorize_seconds);
  s.add("linear_solve_seconds", st.solve_seconds).add("init_seconds", init_seconds);
  if (o.robust != graph::RobustKernel::kNone) s.add("final_robust_cost", st.final_cost);
  res.ok = st.usable();
  res.message = st.usable() ? "" : st.message;
  res.variables = g.graph.variables();
  return res;
}

}  // namespace sextant::tools
