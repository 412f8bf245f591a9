// `sextant optimize` as a function (cli/graph_optimization.hpp): its kinds are parsed once from their spellings,
// an unknown spelling is an error naming the option and the spellings (never a silent default), and the summary
// reports the kinds by the same spellings.
#include "cli/graph_optimization.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

using namespace sextant;
using namespace sextant::tools;

namespace {
std::string text(const Summary& s, const std::string& key) {
  for (const auto& [k, v] : s.entries())
    if (k == key)
      if (const auto* t = std::get_if<std::string>(&v)) return *t;
  return "(missing)";
}
bool has(const Summary& s, const std::string& key) {
  for (const auto& [k, v] : s.entries())
    if (k == key) return true;
  return false;
}
std::string error_of(graph::RobustKernel (*parse)(const std::string&), const std::string& name) {
  try {
    parse(name);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("optimize's kinds: every spelling round-trips, an unknown one is refused with the option and its spellings") {
  CHECK(solver_names() == std::vector<std::string>{"gn", "lm"});
  CHECK(initial_estimate_names() == std::vector<std::string>{"auto", "file", "odometry", "chordal", "sgd"});
  CHECK(graph::robust_kernel_names() == std::vector<std::string>{"none", "huber", "cauchy", "dcs"});
  CHECK(ordering_names() == std::vector<std::string>{"block-amd", "amd", "colamd", "metis", "auto"});
  for (const auto& n : solver_names()) CHECK(name_of(solver_from_name(n)) == n);
  for (const auto& n : initial_estimate_names()) CHECK(name_of(initial_estimate_from_name(n)) == n);
  for (const auto& n : graph::robust_kernel_names())
    CHECK(graph::robust_kernel_name(graph::robust_kernel_from_name(n)) == n);
  for (const auto& n : ordering_names()) CHECK(name_of(ordering_from_name(n)) == n);
  CHECK(graph::robust_kernel_from_name("dcs") == graph::RobustKernel::kDcs);
  CHECK(solver_from_name("lm") == graph::Method::kLevenbergMarquardt);
  CHECK(ordering_from_name("block-amd") == graph::Ordering::kBlockAmd);

  // A misspelt kernel is an error, not "none".
  CHECK(error_of(graph::robust_kernel_from_name, "DCS") == "unknown robust kernel 'DCS' (none, huber, cauchy or dcs)");
  CHECK(error_of(graph::robust_kernel_from_name, "") == "unknown robust kernel '' (none, huber, cauchy or dcs)");
  CHECK_THROWS_WITH_AS(solver_from_name("newton"), "unknown solver 'newton' (gn or lm)", std::invalid_argument);
  CHECK_THROWS_AS(initial_estimate_from_name("Chordal"), std::invalid_argument);
  CHECK_THROWS_AS(ordering_from_name("nested"), std::invalid_argument);
}

TEST_CASE("optimize_graph reports its kinds by their spellings, and a robust kernel's cost only with a kernel") {
  const std::string path = std::string(SEXTANT_SHARED_DIR) + "/data/posegraph/CSAIL.g2o";
  GraphOptimizationOptions o;
  o.solver = graph::Method::kLevenbergMarquardt;
  o.init = InitialEstimate::kChordal;
  o.robust = graph::RobustKernel::kHuber;
  graph::G2oGraph g = graph::read_g2o(path);
  const auto r = optimize_graph(g, o);
  REQUIRE(r.ok);
  CHECK(text(r.summary, "solver") == "lm");
  CHECK(text(r.summary, "init") == "chordal");
  CHECK(text(r.summary, "init_used") == "chordal");
  CHECK(text(r.summary, "robust") == "huber");
  CHECK(has(r.summary, "final_robust_cost"));

  GraphOptimizationOptions plain;
  graph::G2oGraph h = graph::read_g2o(path);
  const auto p = optimize_graph(h, plain);
  REQUIRE(p.ok);
  CHECK(text(p.summary, "solver") == "gn");
  CHECK(text(p.summary, "init") == "auto");
  CHECK((text(p.summary, "init_used") == "chordal" || text(p.summary, "init_used") == "file"));
  CHECK(text(p.summary, "robust") == "none");
  CHECK_FALSE(has(p.summary, "final_robust_cost"));

  GraphOptimizationOptions bad;
  bad.incremental = true;
  bad.solver = graph::Method::kLevenbergMarquardt;
  graph::G2oGraph k = graph::read_g2o(path);
  CHECK_THROWS_AS(optimize_graph(k, bad), std::invalid_argument);
}

TEST_CASE("the default options reach the chordal basin on torus3D, below the file start's local minimum") {
  // From the file's vertices Gauss-Newton (and Ceres) end in a local minimum at 19972.36; the default start (auto)
  // reaches 14574.75 (bench/RESULTS.md, "Batch optimization against Ceres").  About 2 s.
  graph::G2oGraph g = graph::read_g2o(std::string(SEXTANT_SHARED_DIR) + "/data/posegraph/torus3D.g2o");
  const auto r = optimize_graph(g, GraphOptimizationOptions{});
  REQUIRE(r.ok);
  CHECK(text(r.summary, "init") == "auto");
  CHECK(text(r.summary, "init_used") == "chordal");
  CHECK(g.graph.chi2() == doctest::Approx(14574.75).epsilon(1e-6));
}

TEST_CASE(
    "the incremental run's step trace has one line per update that adds up to its summary, with the online chi2 "
    "and the batch optimum's at sampled updates") {
  const std::string path = std::string(SEXTANT_SHARED_DIR) + "/data/posegraph/CSAIL.g2o";
  const std::string trace = "/tmp/sextant_step_trace_test.csv";
  GraphOptimizationOptions o;
  o.incremental = true;
  o.step_trace = trace;
  o.step_reference = 300;
  graph::G2oGraph g = graph::read_g2o(path);
  const auto r = optimize_graph(g, o);
  REQUIRE(r.ok);
  auto number = [&](const std::string& key) {
    for (const auto& [k, v] : r.summary.entries())
      if (k == key) {
        if (const auto* d = std::get_if<double>(&v)) return *d;
        if (const auto* i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
      }
    return -1.0;
  };
  std::ifstream in(trace);
  std::string line;
  REQUIRE(std::getline(in, line));
  CHECK(line ==
        "update,ms,new_factors,relinearized_variables,relinearized_factors,rebuilt,reordering,solves,factor_nonzeros,"
        "chi2,batch_chi2");
  int lines = 0, rebuilt = 0, relinearized = 0, factors = 0, references = 0;
  double ms = 0, chi2 = 0, batch_chi2 = 0;
  while (std::getline(in, line)) {
    std::vector<double> f;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) f.push_back(std::stod(cell));
    REQUIRE((f.size() == 10 || f.size() == 11));
    CHECK(f[0] == ++lines);
    ms += f[1], factors += static_cast<int>(f[2]), relinearized += static_cast<int>(f[4]);
    rebuilt += static_cast<int>(f[5]);
    chi2 = f[9];
    CHECK(chi2 >= 0);
    if (f.size() == 11) {  // every 300th update and the last: the batch optimum is never above the online answer
      CHECK((lines % 300 == 0 || in.peek() == EOF));
      CHECK(f[10] <= chi2 * (1 + 1e-9));
      CHECK(f[10] >= 0.99 * chi2);  // and the online answer is within 1 % of it on CSAIL
      ++references, batch_chi2 = f[10];
    }
  }
  CHECK(references == lines / 300 + 1);
  // The last line's online chi2 is before the final exact back-substitution, which only lowers it to the summary's.
  CHECK(number("final_chi2") <= chi2 * (1 + 1e-9));
  CHECK(batch_chi2 == doctest::Approx(number("batch_final_chi2")).epsilon(1e-6));
  CHECK(lines == number("updates"));
  CHECK(rebuilt == number("rebuilds"));
  CHECK(relinearized == number("relinearized_factors"));
  CHECK(factors <= number("edges"));  // an update that rebuilt reports what it admitted too; none twice
  CHECK(ms / lines == doctest::Approx(number("step_ms_mean")).epsilon(1e-3));
  std::remove(trace.c_str());

  o.step_trace = "/nonexistent-dir/trace.csv";
  graph::G2oGraph h = graph::read_g2o(path);
  CHECK_THROWS_WITH_AS(optimize_graph(h, o), "cannot write the step trace /nonexistent-dir/trace.csv",
                       std::runtime_error);
}
