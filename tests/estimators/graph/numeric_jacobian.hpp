#pragma once
// Central-difference Jacobians of a factor's residual with respect to each of its variables' right perturbations
// (Variable::retract), to check the analytic ones of graph::Factor::linearize.
#include "estimators/graph/factor.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <vector>

namespace sextant::test {

/// d e / d delta_k for every variable k of `f` at `vars`, by central differences of step h.
inline std::vector<Eigen::MatrixXd> numeric_jacobians(const graph::Factor& f, const std::vector<graph::Variable>& vars,
                                                      double h = 1e-6) {
  std::vector<Eigen::MatrixXd> J;
  for (int index : f.variables()) {
    const auto v = static_cast<size_t>(index);
    Eigen::MatrixXd Jk(f.residual_dim(), vars[v].dim());
    for (int c = 0; c < vars[v].dim(); ++c) {
      Eigen::VectorXd d = Eigen::VectorXd::Zero(vars[v].dim());
      std::vector<graph::Variable> plus = vars, minus = vars;
      d[c] = h;
      plus[v].retract(d.data());
      d[c] = -h;
      minus[v].retract(d.data());
      Eigen::VectorXd ep(f.residual_dim()), em(f.residual_dim());
      f.error(plus, ep);
      f.error(minus, em);
      Jk.col(c) = (ep - em) / (2 * h);
    }
    J.push_back(Jk);
  }
  return J;
}

/// The largest difference between the analytic Jacobians of `f` at `vars` and the numeric ones, relative to
/// max(1, the largest analytic entry) of each.
inline double jacobian_mismatch(const graph::Factor& f, const std::vector<graph::Variable>& vars, double h = 1e-6) {
  graph::Linearization l = f.make_linearization(vars);
  f.linearize(vars, l);
  const std::vector<Eigen::MatrixXd> n = numeric_jacobians(f, vars, h);
  double worst = 0;
  for (size_t k = 0; k < n.size(); ++k) {
    const double scale = std::max(1.0, l.jacobians[k].cwiseAbs().maxCoeff());
    worst = std::max(worst, (l.jacobians[k] - n[k]).cwiseAbs().maxCoeff() / scale);
  }
  Eigen::VectorXd e(f.residual_dim());
  f.error(vars, e);
  worst = std::max(worst, (e - l.error).cwiseAbs().maxCoeff());  // linearize's residual is error's
  return worst;
}

}  // namespace sextant::test
