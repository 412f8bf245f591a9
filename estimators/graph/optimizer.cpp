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
  Eigen::VectorXd e, weighted;
  for (const auto& f : g.factors()) {
    const double s = f->chi2(g.variables(), e, weighted);
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
  const DefinitenessCheck check = check_positive_definite(f.information());
  if (check.problem == DefinitenessCheck::Problem::kNone) return "";  // the common case builds no message
  const std::string name =
      "factor " + std::to_string(index) + " (" + f.type() + " on variable " +
      std::to_string(vars[static_cast<size_t>(f.variables()[0])].id) +
      (f.variables().size() > 1 ? " and " + std::to_string(vars[static_cast<size_t>(f.variables()[1])].id) : "") + ")";
  switch (check.problem) {
    case DefinitenessCheck::Problem::kNone:
      return "";
    case DefinitenessCheck::Problem::kNotFinite:
      return name + ": information matrix has a NaN or infinite entry";
    case DefinitenessCheck::Problem::kNotSymmetric:
      return name + ": information matrix is not symmetric";
    case DefinitenessCheck::Problem::kNotPositiveDefinite:
      break;
  }
  std::ostringstream s;
  s << name << ": information matrix is not positive definite (smallest eigenvalue " << check.smallest_eigenvalue
    << ")";
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

namespace {

// One run of the batch optimizer (Gauss-Newton or Levenberg-Marquardt) on a graph, in the steps of its loop.
class OptimizerRun {
 public:
  OptimizerRun(FactorGraph& graph, const OptimizerOptions& o) : graph_(graph), vars_(graph.variables()), o_(o) {}

  OptimizerSummary run() {
    if (auto why = prepare(); !why.empty()) return fail(why);
    sum_.termination = Termination::kMaxIterations;
    sum_.message = "reached the maximum number of iterations";
    while (sum_.iterations < o_.max_iterations) {
      if (relinearize_) relinearize();
      const Step step = iterate();
      if (step == Step::kFailed) return fail(why_);
      if (step == Step::kStop) break;
    }
    return finish();
  }

 private:
  enum class Step { kContinue, kStop, kFailed };

  OptimizerSummary fail(const std::string& why) {
    sum_.termination = Termination::kFailure;
    sum_.message = why;
    sum_.total_seconds = seconds_since(start_);
    return sum_;
  }

  // Checks the graph, fixes its first pose when nothing fixes the gauge (if asked), sets up the normal equations,
  // the linearizations and the initial cost.  Returns why it cannot run, or "".
  std::string prepare() {
    if (auto why = validate(graph_); !why.empty()) return why;
    if (vars_.empty()) return "the graph has no variables";
    if (!graph_.has_gauge() && o_.fix_first_pose_if_no_gauge) {
      for (auto& v : vars_)
        if (v.is_pose()) {
          v.fixed = true;
          break;
        }
    }
    try {
      ne_ = std::make_unique<SparseNormalEquations>(graph_, o_.ordering);
    } catch (const std::exception& e) {
      return e.what();
    }
    lin_.reserve(graph_.factors().size());
    for (const auto& f : graph_.factors()) lin_.push_back(f->make_linearization(vars_));
    cost_ = evaluate(graph_, o_);
    sum_.initial_chi2 = cost_.chi2;
    sum_.initial_cost = cost_.robust;
    if (!std::isfinite(cost_.robust)) return "the initial cost is not finite";
    lambda_ = o_.initial_lambda;
    best_cost_ = cost_;
    return "";
  }

  // The normal equations at the current estimate, each factor weighted by its robust kernel.
  void relinearize() {
    const auto tl = Clock::now();
    ne_->clear();
    const auto& factors = graph_.factors();
    for (size_t i = 0; i < factors.size(); ++i) {
      factors[i]->linearize(vars_, lin_[i]);
      const double s = factors[i]->weighted_square(lin_[i].error, weighted_);
      ne_->add(static_cast<int>(i), *factors[i], lin_[i], robust_weight(o_.kernel, o_.kernel_width, s));
    }
    sum_.linearize_seconds += seconds_since(tl);
    relinearize_ = false;
  }

  // One iteration: solve for the step, apply it, judge it (accept_lm / accept_gauss_newton).
  Step iterate() {
    const bool lm = o_.method == Method::kLevenbergMarquardt;
    std::string why;
    ++sum_.iterations;
    if (!ne_->solve(lm ? lambda_ : 0.0, dx_, &why)) {
      if (lm && lambda_ < 1e10) {  // damping may rescue an indefinite step; a singular system stays singular
        lambda_ *= nu_, nu_ *= 2;
        if (sum_.iterations > 1) return Step::kContinue;
      }
      sum_.factorize_seconds = ne_->factorization_seconds();
      sum_.solve_seconds = ne_->solve_seconds();
      sum_.final_chi2 = cost_.chi2;
      sum_.final_cost = cost_.robust;
      why_ = why;
      return Step::kFailed;
    }
    backup_ = vars_;
    for (size_t v = 0; v < vars_.size(); ++v) {
      const int off = ne_->offset(static_cast<int>(v));
      if (off >= 0) vars_[v].retract(dx_.data() + off);
    }
    const Cost next = evaluate(graph_, o_);
    return lm ? accept_lm(next) : accept_gauss_newton(next);
  }

  bool small_decrease(double decrease, const Cost& next) const {
    return decrease < o_.relative_tolerance * std::max(next.robust, 1e-300) + 1e-300;
  }

  Step converged() {
    sum_.termination = Termination::kConverged;
    sum_.message = "relative decrease of the cost below the tolerance";
    return Step::kStop;
  }

  // Levenberg-Marquardt: the step is kept when the cost decreased (gain ratio rho > 0 against the linear model's
  // decrease -g'dx + lambda dx' D dx, the cost without the 1/2), lambda then scaled by max(1/3, 1 - (2 rho - 1)^3)
  // (Nielsen); else undone and lambda raised.
  Step accept_lm(const Cost& next) {
    const double decrease = cost_.robust - next.robust;
    const Eigen::VectorXd d = ne_->diagonal().cwiseMax(1e-6);
    const double predicted = -ne_->gradient().dot(dx_) + lambda_ * dx_.dot(d.cwiseProduct(dx_));
    const double rho = predicted > 0 ? decrease / predicted : -1;
    if (std::isfinite(next.robust) && rho > 0) {
      lambda_ *= std::max(1.0 / 3.0, 1 - std::pow(2 * rho - 1, 3));
      nu_ = 2;
      cost_ = next;
      relinearize_ = true;
      return small_decrease(decrease, next) ? converged() : Step::kContinue;
    }
    vars_ = backup_;
    lambda_ *= nu_, nu_ *= 2;
    if (lambda_ > 1e16) {
      sum_.termination = Termination::kNoProgress;
      sum_.message = "no step decreases the cost (damping at its maximum)";
      return Step::kStop;
    }
    return Step::kContinue;
  }

  // Plain Gauss-Newton takes every finite step (as g2o does): on hard graphs (city10000) the cost may rise for an
  // iteration on the way to the optimum.  The best estimate seen is kept.
  Step accept_gauss_newton(const Cost& next) {
    const double decrease = cost_.robust - next.robust;
    if (!std::isfinite(next.robust)) {
      vars_ = backup_;
      sum_.termination = Termination::kNoProgress;
      sum_.message = "the Gauss-Newton step produced a non-finite cost; stopped at the previous estimate";
      return Step::kStop;
    }
    if (next.robust < best_cost_.robust)
      best_cost_ = next, best_ = {};
    else if (best_.empty())
      best_ = backup_, best_cost_ = cost_;
    cost_ = next;
    relinearize_ = true;
    return decrease >= 0 && small_decrease(decrease, next) ? converged() : Step::kContinue;
  }

  // The best estimate seen back in place, the summary's costs and times.
  OptimizerSummary finish() {
    if (!best_.empty() && best_cost_.robust < cost_.robust) {
      vars_ = best_;
      cost_ = best_cost_;
    }
    sum_.final_chi2 = cost_.chi2;
    sum_.final_cost = cost_.robust;
    sum_.factorize_seconds = ne_->factorization_seconds();
    sum_.solve_seconds = ne_->solve_seconds();
    sum_.total_seconds = seconds_since(start_);
    return sum_;
  }

  FactorGraph& graph_;
  std::vector<Variable>& vars_;
  const OptimizerOptions& o_;
  const Clock::time_point start_ = Clock::now();
  OptimizerSummary sum_;
  std::unique_ptr<SparseNormalEquations> ne_;
  std::vector<Linearization> lin_;
  Cost cost_, best_cost_;
  double lambda_ = 0, nu_ = 2;
  bool relinearize_ = true;
  Eigen::VectorXd dx_, weighted_;
  std::vector<Variable> backup_, best_;  // `best_` is empty while the current estimate is the best seen
  std::string why_;                      // why the last solve failed
};

}  // namespace

OptimizerSummary optimize(FactorGraph& graph, const OptimizerOptions& o) { return OptimizerRun(graph, o).run(); }

}  // namespace sextant::graph
