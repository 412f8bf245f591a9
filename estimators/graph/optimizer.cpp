#include "estimators/graph/optimizer.hpp"

#include "estimators/graph/sparse_normal_equations.hpp"
#include "estimators/spd_matrix.hpp"

#include <Eigen/Eigenvalues>

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

namespace sextant::graph {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Cost {
  double chi2 = 0, robust = 0;
};

Cost evaluate(const FactorGraph& g, const OptimizerOptions& o) {
  Cost c;
  Eigen::VectorXd e;
  for (const auto& f : g.factors()) {
    e.resize(f->residual_dim());
    f->error(g.variables(), e);
    const double s = e.dot(f->information() * e);
    c.chi2 += s;
    c.robust += robust_cost(o.kernel, o.kernel_width, s);
  }
  return c;
}

}  // namespace

std::string validate_factor(const std::vector<Variable>& vars, const Factor& f, size_t index) {
  for (int v : f.variables())
    if (v < 0 || static_cast<size_t>(v) >= vars.size())
      return "factor " + std::to_string(index) + " (" + f.type() + ") refers to a variable that does not exist";
  const auto& I = f.information();
  const std::string name = "factor " + std::to_string(index) + " (" + f.type() + " on variable " +
                           std::to_string(vars[static_cast<size_t>(f.variables()[0])].id) +
                           (f.variables().size() > 1 ? " and " + std::to_string(vars[static_cast<size_t>(f.variables()[1])].id) : "") + ")";
  const DefinitenessCheck check = check_positive_definite(I);
  switch (check.problem) {
    case DefinitenessCheck::Problem::kNone: return "";
    case DefinitenessCheck::Problem::kNotFinite: return name + ": information matrix has a NaN or infinite entry";
    case DefinitenessCheck::Problem::kNotSymmetric: return name + ": information matrix is not symmetric";
    case DefinitenessCheck::Problem::kNotPositiveDefinite: break;
  }
  std::ostringstream s;
  s << name << ": information matrix is not positive definite (smallest eigenvalue " << check.smallest_eigenvalue << ")";
  return s.str();
}

std::string validate(const FactorGraph& g) {
  const auto& vars = g.variables();
  for (const auto& v : vars)
    if (!v.finite()) return "variable " + std::to_string(v.id) + " has a NaN or infinite value";
  for (size_t i = 0; i < g.factors().size(); ++i)
    if (auto why = validate_factor(vars, *g.factors()[i], i); !why.empty()) return why;
  return "";
}

OptimizerSummary optimize(FactorGraph& graph, const OptimizerOptions& o) {
  const auto start = Clock::now();
  OptimizerSummary sum;
  auto fail = [&](const std::string& why) {
    sum.termination = Termination::kFailure;
    sum.message = why;
    sum.total_seconds = seconds_since(start);
    return sum;
  };
  if (auto why = validate(graph); !why.empty()) return fail(why);
  auto& vars = graph.variables();
  if (vars.empty()) return fail("the graph has no variables");

  if (!graph.has_gauge() && o.fix_first_pose_if_no_gauge) {
    for (auto& v : vars)
      if (v.is_pose()) {
        v.fixed = true;
        break;
      }
  }

  std::unique_ptr<SparseNormalEquations> ne;
  try {
    ne = std::make_unique<SparseNormalEquations>(graph, o.ordering);
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  std::vector<Linearization> lin;
  lin.reserve(graph.factors().size());
  for (const auto& f : graph.factors()) lin.push_back(f->make_linearization(vars));

  Cost cost = evaluate(graph, o);
  sum.initial_chi2 = cost.chi2;
  sum.initial_cost = cost.robust;
  if (!std::isfinite(cost.robust)) return fail("the initial cost is not finite");

  double lambda = o.initial_lambda, nu = 2;
  bool relinearize = true;
  Eigen::VectorXd dx;
  std::vector<Variable> backup, best;  // `best` is empty while the current estimate is the best seen
  Cost best_cost = cost;
  sum.termination = Termination::kMaxIterations;
  sum.message = "reached the maximum number of iterations";
  while (sum.iterations < o.max_iterations) {
    if (relinearize) {
      const auto tl = Clock::now();
      ne->clear();
      const auto& factors = graph.factors();
      for (size_t i = 0; i < factors.size(); ++i) {
        factors[i]->linearize(vars, lin[i]);
        const double s = lin[i].error.dot(factors[i]->information() * lin[i].error);
        ne->add(static_cast<int>(i), *factors[i], lin[i], robust_weight(o.kernel, o.kernel_width, s));
      }
      sum.linearize_seconds += seconds_since(tl);
      relinearize = false;
    }
    const bool lm = o.method == Method::kLevenbergMarquardt;
    std::string why;
    ++sum.iterations;
    if (!ne->solve(lm ? lambda : 0.0, dx, &why)) {
      if (lm && lambda < 1e10) {  // damping may rescue an indefinite step; a singular system stays singular
        lambda *= nu, nu *= 2;
        if (sum.iterations > 1) continue;
      }
      sum.factorize_seconds = ne->factorization_seconds();
      sum.solve_seconds = ne->solve_seconds();
      sum.final_chi2 = cost.chi2;
      sum.final_cost = cost.robust;
      return fail(why);
    }
    backup = vars;
    for (size_t v = 0; v < vars.size(); ++v) {
      const int off = ne->offset(static_cast<int>(v));
      if (off >= 0) vars[v].retract(dx.data() + off);
    }
    const Cost next = evaluate(graph, o);
    const double decrease = cost.robust - next.robust;
    if (lm) {
      // Gain ratio against the linear model's decrease: -g'dx + lambda dx' D dx (cost without the 1/2).
      const Eigen::VectorXd d = ne->diagonal().cwiseMax(1e-6);
      const double predicted = -ne->gradient().dot(dx) + lambda * dx.dot(d.cwiseProduct(dx));
      const double rho = predicted > 0 ? decrease / predicted : -1;
      if (std::isfinite(next.robust) && rho > 0) {
        lambda *= std::max(1.0 / 3.0, 1 - std::pow(2 * rho - 1, 3));
        nu = 2;
        cost = next;
        relinearize = true;
        if (decrease < o.relative_tolerance * std::max(next.robust, 1e-300) + 1e-300) {
          sum.termination = Termination::kConverged;
          sum.message = "relative decrease of the cost below the tolerance";
          break;
        }
      } else {
        vars = backup;
        lambda *= nu, nu *= 2;
        if (lambda > 1e16) {
          sum.termination = Termination::kNoProgress;
          sum.message = "no step decreases the cost (damping at its maximum)";
          break;
        }
      }
    } else {
      // Plain Gauss-Newton takes every finite step (as g2o does): on hard graphs (city10000) the cost may rise for
      // an iteration on the way to the optimum.  The best estimate seen is kept.
      if (!std::isfinite(next.robust)) {
        vars = backup;
        sum.termination = Termination::kNoProgress;
        sum.message = "the Gauss-Newton step produced a non-finite cost; stopped at the previous estimate";
        break;
      }
      if (next.robust < best_cost.robust) best_cost = next, best = {};
      else if (best.empty()) best = backup, best_cost = cost;
      cost = next;
      relinearize = true;
      if (decrease >= 0 && decrease < o.relative_tolerance * std::max(next.robust, 1e-300) + 1e-300) {
        sum.termination = Termination::kConverged;
        sum.message = "relative decrease of the cost below the tolerance";
        break;
      }
    }
  }
  if (!best.empty() && best_cost.robust < cost.robust) {
    vars = best;
    cost = best_cost;
  }
  sum.final_chi2 = cost.chi2;
  sum.final_cost = cost.robust;
  sum.factorize_seconds = ne->factorization_seconds();
  sum.solve_seconds = ne->solve_seconds();
  sum.total_seconds = seconds_since(start);
  return sum;
}

}  // namespace sextant::graph
