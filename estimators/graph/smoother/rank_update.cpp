#include "estimators/graph/smoother/rank_update.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <string>
#include <utility>

namespace sextant::graph::smoother {

Contribution linearize(const SmootherState& s, size_t fi) {
  const Factor& f = *s.graph.factors()[fi];
  Linearization lin = f.make_linearization(s.lin);
  f.linearize(s.lin, lin);
  Eigen::VectorXd weighted;
  const Eigen::MatrixXd W = s.kernel_weight(fi, f.weighted_square(lin.error, weighted)) * f.information();
  const Eigen::MatrixXd U = W.llt().matrixU();
  Contribution c;
  std::vector<std::pair<int, int>> blocks;  // (first column, variable slot in the factor)
  for (size_t k = 0; k < f.variables().size(); ++k) {
    const int p = s.pos[static_cast<size_t>(f.variables()[k])];
    if (p >= 0) blocks.emplace_back(p, static_cast<int>(k));
  }
  std::sort(blocks.begin(), blocks.end());
  int width = 0;
  for (auto [p, k] : blocks) width += static_cast<int>(lin.jacobians[static_cast<size_t>(k)].cols());
  c.Ct.resize(f.residual_dim(), width);
  c.grad.resize(width);
  int at = 0;
  for (auto [p, k] : blocks) {
    const Eigen::MatrixXd& J = lin.jacobians[static_cast<size_t>(k)];
    c.Ct.middleCols(at, J.cols()) = U * J;
    c.grad.segment(at, J.cols()) = J.transpose() * (W * lin.error);
    for (int d = 0; d < J.cols(); ++d) c.cols.push_back(p + d);
    at += static_cast<int>(J.cols());
  }
  return c;
}

namespace {

bool failed(SmootherState& s, const std::string& what) {
  s.cholmod_failure = what + " (CHOLMOD status " + std::to_string(s.workspace->status) + ")";
  return false;
}

// CHOLMOD gives a column that outgrows its space new room at the end of L's storage and leaves a hole behind; when
// the end is reached it reallocates L to 1.2 times everything allocated, holes included, and only then packs.  On
// city10000 that tripled the storage, and the fresh pages cost single updates 50-150 ms of page faults.  So before a
// modification that could run past the end, the columns are packed in place and the end is moved back to the last
// column: the holes are reused, and L grows (once, with headroom) only when the packed columns need it.
bool make_room(SmootherState& s, const cholmod_sparse* C) {
  // What the modification can claim at the end: every column j on its paths may move there, and CHOLMOD gives a
  // moved column grow1 x its new count + grow2, at most n - j (cholmod_reallocate_column).  Its new pattern is its
  // old one, the rows of C on its path, and the new rows of its child on the path (Davis and Hager 2001); while the
  // elimination tree keeps its shape those are rows of C, so it gains at most the R distinct rows of C.  That is an
  // estimate, not a bound (a new parent brings its child's old rows); when it falls short CHOLMOD grows L itself,
  // which is right, only slower.  Measured on city10000, sphere2500 and M3500: no update used more than the estimate
  // (bench/RESULTS.md); the former 2 Lnz + 16 made city10000 grow L 55 times by more than 5 ms each.
  Factorization& fx = s.fx;
  cholmod_factor* L = fx.L.get();
  std::vector<char>& on_path = fx.on_path;
  const int* Ci = static_cast<const int*>(C->i);
  const int* Cp = static_cast<const int*>(C->p);
  const int* Lnz = static_cast<const int*>(L->nz);
  const size_t n = L->n;
  size_t rows = 0;
  const size_t entries = static_cast<size_t>(Cp[C->ncol]);
  for (size_t k = 0; k < entries; ++k)
    if (!on_path[static_cast<size_t>(Ci[k])]) on_path[static_cast<size_t>(Ci[k])] = 1, ++rows;
  for (size_t k = 0; k < entries; ++k) on_path[static_cast<size_t>(Ci[k])] = 0;
  const double grow1 = std::max(1.0, s.workspace->grow1);
  size_t need = 0;
  for (size_t k = 0; k < C->ncol; ++k)
    for (int j = Ci[Cp[k]]; j >= 0 && !on_path[static_cast<size_t>(j)]; j = fx.parent_of(j)) {
      on_path[static_cast<size_t>(j)] = 1;
      const double grown =
          grow1 * static_cast<double>(static_cast<size_t>(Lnz[j]) + rows) + static_cast<double>(s.workspace->grow2);
      need += std::min(static_cast<size_t>(grown) + 16, n - static_cast<size_t>(j));
    }
  for (size_t k = 0; k < C->ncol; ++k)
    for (int j = Ci[Cp[k]]; j >= 0 && on_path[static_cast<size_t>(j)]; j = fx.parent_of(j))
      on_path[static_cast<size_t>(j)] = 0;
  int* Lp = static_cast<int*>(L->p);
  if (static_cast<size_t>(Lp[n]) + need <= L->nzmax) return true;
  if (!cholmod_pack_factor(L, s.workspace.get())) return failed(s, "CHOLMOD could not pack the factor");
  // The end of the storage (Lp[n]) is left where it was by the packing; the last column in storage order keeps
  // what it uses plus grow2, as packing gives every column.
  const int last = static_cast<const int*>(L->prev)[n];
  Lp[n] = Lp[last] + static_cast<int>(
                         std::min(static_cast<size_t>(Lnz[last]) + s.workspace->grow2, n - static_cast<size_t>(last)));
  const size_t end = static_cast<size_t>(Lp[n]);
  if (end + need > L->nzmax && !cholmod_reallocate_factor(end + need + end / 2, L, s.workspace.get()))
    return failed(s, "CHOLMOD could not grow the factor");
  return true;
}

}  // namespace

bool apply(SmootherState& s, const std::vector<Contribution>& cs, bool add, bool within_pattern) {
  // One rank-k modification for all of them: CHOLMOD walks each elimination-tree path once per 8 columns of C
  // instead of once per factor, which is what a loop closure's long path costs.
  Factorization& fx = s.fx;
  size_t r = 0, nz = 0;
  for (const Contribution& c : cs)
    if (!c.cols.empty()) r += static_cast<size_t>(c.Ct.rows()), nz += static_cast<size_t>(c.Ct.rows()) * c.cols.size();
  if (r == 0) return true;
  SparsePtr C =
      own(cholmod_allocate_sparse(static_cast<size_t>(fx.capacity), r, nz, 1, 1, 0, CHOLMOD_REAL, s.workspace.get()),
          s.workspace);
  if (C == nullptr) return failed(s, "CHOLMOD could not allocate an update");
  int* p = static_cast<int*>(C->p);
  int* i = static_cast<int*>(C->i);
  double* x = static_cast<double*>(C->x);
  size_t col = 0, at = 0;
  for (const Contribution& c : cs) {
    if (c.cols.empty()) continue;
    for (Eigen::Index k = 0; k < c.Ct.rows(); ++k, ++col) {
      p[col] = static_cast<int>(at);
      for (size_t j = 0; j < c.cols.size(); ++j, ++at) {
        i[at] = c.cols[j];
        x[at] = c.Ct(k, static_cast<Eigen::Index>(j));
      }
    }
  }
  p[r] = static_cast<int>(at);
  // b = -g changes by -(+-grad) on the factor's columns, all of which lie on the modified paths.
  double* db = static_cast<double*>(fx.delta_b->x);
  for (const Contribution& c : cs)
    for (size_t j = 0; j < c.cols.size(); ++j) {
      const double d = add ? c.grad[static_cast<Eigen::Index>(j)] : -c.grad[static_cast<Eigen::Index>(j)];
      fx.g[c.cols[j]] += d;
      db[c.cols[j]] -= d;
    }
  if (!within_pattern && !make_room(s, C.get())) return false;
  const bool ok = !s.workspace.take_fault() && cholmod_updown_solve(add ? 1 : 0, C.get(), fx.L.get(), fx.y.get(),
                                                                    fx.delta_b.get(), s.workspace.get());
  if (!ok) return failed(s, "CHOLMOD's update of the factor failed");
  // The columns CHOLMOD modified: the elimination-tree paths from each column's first row to the root.
  const int* Ci = static_cast<const int*>(C->i);
  const int* Cp = static_cast<const int*>(C->p);
  for (size_t k = 0; k < r; ++k)
    for (int j = Ci[Cp[k]]; j >= 0 && !fx.dirty[static_cast<size_t>(j)]; j = fx.parent_of(j))
      fx.dirty[static_cast<size_t>(j)] = 1;
  return true;
}

bool enter_by_rank_updates(SmootherState& s, const Admission& a, bool& definite) {
  Factorization& fx = s.fx;
  const auto& vars = s.graph.variables();
  for (int v : a.vars_in) {
    if (vars[static_cast<size_t>(v)].fixed) continue;
    s.pos[static_cast<size_t>(v)] = fx.used;
    for (int k = 0; k < vars[static_cast<size_t>(v)].dim(); ++k) fx.col_var[static_cast<size_t>(fx.used + k)] = v;
    fx.used += vars[static_cast<size_t>(v)].dim();
  }
  std::vector<Contribution> added;
  added.reserve(a.factors_in.size());
  for (size_t f : a.factors_in) added.push_back(linearize(s, f));
  if (!apply(s, added, true)) return false;
  for (size_t f : a.factors_in) {
    s.weight[f] = 1.0;
    ++s.factors_in_system;
    for (int v : s.graph.factors()[f]->variables()) s.var_factors[static_cast<size_t>(v)].push_back(f);
  }
  // Remove the identity that held each newly used column.
  std::vector<Contribution> identities;
  for (int v : a.vars_in) {
    const int p = s.pos[static_cast<size_t>(v)];
    if (p < 0) continue;
    Contribution id;
    const int d = vars[static_cast<size_t>(v)].dim();
    id.Ct = Eigen::MatrixXd::Identity(d, d);
    id.grad = Eigen::VectorXd::Zero(d);
    for (int k = 0; k < d; ++k) id.cols.push_back(p + k);
    identities.push_back(std::move(id));
  }
  if (!apply(s, identities, false, true)) return false;
  definite = true;
  const int* Lp = static_cast<const int*>(fx.L->p);
  const double* Lx = static_cast<const double*>(fx.L->x);
  for (const Contribution& id : identities)
    for (int c : id.cols)
      if (!(Lx[Lp[c]] > 0)) definite = false;
  s.pending_vars = a.vars_wait;
  s.pending_factors = a.factors_wait;
  return true;
}

}  // namespace sextant::graph::smoother
