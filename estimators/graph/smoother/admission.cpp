#include "estimators/graph/smoother/admission.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>

namespace sextant::graph::smoother {

void hold_gauge(SmootherState& s) {
  if (s.gauge_checked || s.graph.variables().empty()) return;
  if (!s.graph.has_gauge())
    for (size_t v = 0; v < s.graph.variables().size(); ++v)
      if (s.graph.variables()[v].is_pose()) {
        s.graph.variables()[v].fixed = s.lin[v].fixed = true;
        break;
      }
  s.gauge_checked = true;
}

namespace {

// ready[k]: whether new_vars[k] is determined by the new factors all of whose variables are in the system, fixed, or
// ready themselves (iterated until no variable drops out).
void find_determined(const SmootherState& s, const std::vector<int>& new_vars, const std::vector<size_t>& new_factors,
                     std::vector<char>& ready) {
  const auto& vars = s.graph.variables();
  std::vector<int> slot(vars.size(), -1);
  for (size_t k = 0; k < new_vars.size(); ++k) slot[static_cast<size_t>(new_vars[k])] = static_cast<int>(k);
  ready.assign(new_vars.size(), 1);
  Linearization lin;    // reused from factor to factor: a rebuild after lifelong thinning admits every factor
  Eigen::MatrixXd JtW;  // J' Omega
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<Eigen::MatrixXd> info(new_vars.size());
    for (size_t k = 0; k < new_vars.size(); ++k) {
      const int d = vars[static_cast<size_t>(new_vars[k])].dim();
      info[k] = Eigen::MatrixXd::Zero(d, d);
    }
    for (size_t fi : new_factors) {
      const Factor& f = *s.graph.factors()[fi];
      bool ok = true;
      for (int v : f.variables()) {
        const int sl = slot[static_cast<size_t>(v)];
        if (sl >= 0 && !ready[static_cast<size_t>(sl)]) ok = false;
        if (sl < 0 && s.pos[static_cast<size_t>(v)] < 0 && !vars[static_cast<size_t>(v)].fixed) ok = false;
      }
      if (!ok) continue;
      f.shape(lin, s.lin);
      f.linearize(s.lin, lin);
      for (size_t k = 0; k < f.variables().size(); ++k) {
        const int sl = slot[static_cast<size_t>(f.variables()[k])];
        if (sl < 0) continue;
        JtW.noalias() = lin.jacobians[k].transpose() * f.information();
        info[static_cast<size_t>(sl)].noalias() += JtW * lin.jacobians[k];
      }
    }
    for (size_t k = 0; k < new_vars.size(); ++k) {
      if (!ready[k] || vars[static_cast<size_t>(new_vars[k])].fixed) continue;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(info[k], Eigen::EigenvaluesOnly);
      const double top = eig.eigenvalues().cwiseAbs().maxCoeff();
      if (!(eig.eigenvalues().minCoeff() > 1e-12 * std::max(top, 1e-300))) ready[k] = 0, changed = true;
    }
  }
}

}  // namespace

Admission admit(const SmootherState& s) {
  const auto& vars = s.graph.variables();
  std::vector<char> ready;
  find_determined(s, s.pending_vars, s.pending_factors, ready);
  Admission a;
  for (size_t k = 0; k < s.pending_vars.size(); ++k) {
    const int v = s.pending_vars[k];
    if (!ready[k]) {
      a.vars_wait.push_back(v);
      continue;
    }
    a.vars_in.push_back(v);
    if (!vars[static_cast<size_t>(v)].fixed) a.new_dim += vars[static_cast<size_t>(v)].dim();
  }
  // The pending factors all of whose variables are in the system or entering it now.
  std::vector<char> entering_var(vars.size(), 0);
  for (int v : a.vars_in) entering_var[static_cast<size_t>(v)] = 1;
  for (size_t f : s.pending_factors) {
    bool ok = true;
    for (int v : s.graph.factors()[f]->variables()) {
      const size_t vi = static_cast<size_t>(v);
      if (s.pos[vi] < 0 && !vars[vi].fixed && !entering_var[vi]) ok = false;
    }
    (ok ? a.factors_in : a.factors_wait).push_back(f);
  }
  return a;
}

std::vector<char> admit_for_rebuild(SmootherState& s, IncrementalStatus& st) {
  std::vector<char> in(s.graph.variables().size(), 0);
  for (size_t v = 0; v < s.pos.size(); ++v) {
    in[v] = s.pos[v] >= 0 || s.graph.variables()[v].fixed;
    if (s.pos[v] >= 0) s.lin[v] = s.graph.variables()[v];
  }
  std::vector<char> ready;
  find_determined(s, s.pending_vars, s.pending_factors, ready);
  std::vector<int> wait;
  for (size_t k = 0; k < s.pending_vars.size(); ++k) {
    if (ready[k]) {
      in[static_cast<size_t>(s.pending_vars[k])] = 1;
      ++st.new_variables;
    } else {
      wait.push_back(s.pending_vars[k]);
    }
  }
  std::vector<size_t> factors_wait;
  for (size_t f : s.pending_factors) {
    bool ok = true;
    for (int v : s.graph.factors()[f]->variables()) ok = ok && in[static_cast<size_t>(v)];
    if (ok) {
      s.weight[f] = 1.0, ++st.new_factors, ++s.factors_in_system;
      for (int v : s.graph.factors()[f]->variables()) s.var_factors[static_cast<size_t>(v)].push_back(f);
    } else {
      factors_wait.push_back(f);
    }
  }
  s.pending_vars = wait;
  s.pending_factors = factors_wait;
  st.deferred_variables = static_cast<int>(wait.size());
  return in;
}

}  // namespace sextant::graph::smoother
