#include "estimators/graph/incremental_smoother.hpp"

#include "estimators/graph/block_ordering.hpp"
#include "estimators/graph/optimizer.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <limits>
#include <chrono>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <type_traits>

namespace sextant::graph {

/// One factor's share of the normal equations at the linearization point: H_f = C C', g_f = grad, where
/// C' = U J over the factor's free columns (W = U'U, W = w Omega with the robust weight w).
struct IncrementalSmoother::Contribution {
  std::vector<int> cols;  // ascending
  Eigen::MatrixXd Ct;     // residual_dim x cols.size()
  Eigen::VectorXd grad;   // cols.size()
};

namespace {
struct Never {  // the deadline of work that must finish now
  bool operator()() const { return false; }
};
}  // namespace

/// A linearized system being built: which factors, at which linearization point, in which column positions, and
/// its normal equations and factor as far as they got.
struct IncrementalSmoother::System {
  explicit System(cholmod_common* c) : common(c) {}
  ~System() {
    if (H) cholmod_free_sparse(&H, common);
    if (L) cholmod_free_factor(&L, common);
    if (y) cholmod_free_dense(&y, common);
  }
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  cholmod_common* common;
  std::vector<size_t> factors;  // the factors in the system, ascending
  std::vector<Variable> lin;    // the linearization point: every variable's estimate when the system was begun
  std::vector<int> pos;         // per variable: first column, -1 when not in the system
  std::vector<int> col_var;     // per column: the variable, -1 for a reserved column
  // Columns [0, used): variables; [used, reserve_end): reserved for new variables (identity); [reserve_end,
  // capacity): the hub variables (landmarks), kept after the reserved columns (order_blocks says why).
  int used = 0, reserve_end = 0, capacity = 0;
  // H's column pattern by variable: the variables before it in the ordering that share a factor with it, by position
  // (flat: before[first[v] .. first[v] + count[v])); its own block comes last in each of its columns.
  std::vector<int> first, count, before;
  cholmod_sparse* H = nullptr;  // upper triangle; freed once factorized
  Eigen::VectorXd g;
  cholmod_factor* L = nullptr;
  cholmod_dense* y = nullptr;   // L^-1 (-g)
  size_t assembled = 0;         // factors linearized into H and g
  size_t factorized = 0;        // rows of L computed
  bool done = false;
  std::string error;            // why it failed (when done)
};

namespace {

bool is_rotation_component(VariableKind k, int i) {
  return (k == VariableKind::kPose2 && i == 2) || (k == VariableKind::kPose3 && i >= 3);
}

}  // namespace

IncrementalSmoother::IncrementalSmoother(IncrementalOptions options) : options_(options) {
  cholmod_start(&common_);
  common_.print = 0;
}

IncrementalSmoother::~IncrementalSmoother() {
  if (L_) cholmod_free_factor(&L_, &common_);
  if (y_) cholmod_free_dense(&y_, &common_);
  if (delta_b_) cholmod_free_dense(&delta_b_, &common_);
  cholmod_finish(&common_);
}

int IncrementalSmoother::add_variable(const Variable& v) {
  if (!v.finite()) throw std::invalid_argument("variable " + std::to_string(v.id) + " has a NaN or infinite value");
  const int i = graph_.add_variable(v);  // throws for a duplicate id
  lin_.push_back(v);
  pos_.push_back(-1);
  var_factors_.emplace_back();
  pending_vars_.push_back(i);
  return i;
}

void IncrementalSmoother::add_factor(std::unique_ptr<Factor> factor, bool robust, std::optional<double> kernel_width) {
  if (auto why = validate_factor(graph_.variables(), *factor, graph_.factors().size()); !why.empty())
    throw std::invalid_argument(why);
  if (kernel_width && !(std::isfinite(*kernel_width) && *kernel_width > 0))
    throw std::invalid_argument("factor " + std::to_string(graph_.factors().size()) + ": kernel width " +
                                std::to_string(*kernel_width) + " is not a positive finite number");
  pending_factors_.push_back(graph_.factors().size());
  weight_.push_back(0.0);
  kernel_width_.push_back(robust ? kernel_width.value_or(options_.kernel_width) : 0.0);
  graph_.add_factor(std::move(factor));
}

size_t IncrementalSmoother::factor_nonzeros() const {
  if (L_ == nullptr) return 0;
  const int* nz = static_cast<const int*>(L_->nz);
  size_t s = 0;
  for (size_t j = 0; j < L_->n; ++j) s += static_cast<size_t>(nz[j]);
  return s;
}

double IncrementalSmoother::kernel_weight(size_t fi, double chi2) const {
  return kernel_width_[fi] > 0 ? robust_weight(options_.kernel, kernel_width_[fi], chi2) : 1.0;
}

IncrementalSmoother::Contribution IncrementalSmoother::linearize(size_t fi) const {
  const Factor& f = *graph_.factors()[fi];
  Linearization lin = f.make_linearization(lin_);
  f.linearize(lin_, lin);
  const Eigen::MatrixXd W = kernel_weight(fi, lin.error.dot(f.information() * lin.error)) * f.information();
  const Eigen::MatrixXd U = W.llt().matrixU();
  Contribution c;
  std::vector<std::pair<int, int>> blocks;  // (first column, variable slot in the factor)
  for (size_t k = 0; k < f.variables().size(); ++k) {
    const int p = pos_[static_cast<size_t>(f.variables()[k])];
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

void IncrementalSmoother::apply(const std::vector<Contribution>& cs, bool add, bool within_pattern) {
  // One rank-k modification for all of them: CHOLMOD walks each elimination-tree path once per 8 columns of C
  // instead of once per factor, which is what a loop closure's long path costs.
  size_t r = 0, nz = 0;
  for (const Contribution& c : cs)
    if (!c.cols.empty()) r += static_cast<size_t>(c.Ct.rows()), nz += static_cast<size_t>(c.Ct.rows()) * c.cols.size();
  if (r == 0) return;
  cholmod_sparse* C = cholmod_allocate_sparse(static_cast<size_t>(capacity_), r, nz, 1, 1, 0, CHOLMOD_REAL, &common_);
  if (C == nullptr) throw std::runtime_error("CHOLMOD could not allocate an update");
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
  double* db = static_cast<double*>(delta_b_->x);
  for (const Contribution& c : cs)
    for (size_t j = 0; j < c.cols.size(); ++j) {
      const double d = add ? c.grad[static_cast<Eigen::Index>(j)] : -c.grad[static_cast<Eigen::Index>(j)];
      g_[c.cols[j]] += d;
      db[c.cols[j]] -= d;
    }
  if (!within_pattern) make_room(C);
  const int ok = cholmod_updown_solve(add ? 1 : 0, C, L_, y_, delta_b_, &common_);
  if (ok) {
    // The columns CHOLMOD modified: the elimination-tree paths from each column's first row to the root.
    const int* Ci = static_cast<const int*>(C->i);
    const int* Cp = static_cast<const int*>(C->p);
    for (size_t k = 0; k < r; ++k)
      for (int j = Ci[Cp[k]]; j >= 0 && !dirty_[static_cast<size_t>(j)]; j = parent_of(j)) dirty_[static_cast<size_t>(j)] = 1;
  }
  cholmod_free_sparse(&C, &common_);
  if (!ok) throw std::runtime_error("CHOLMOD's update of the factor failed (status " + std::to_string(common_.status) + ")");
}

// CHOLMOD gives a column that outgrows its space new room at the end of L's storage and leaves a hole behind; when
// the end is reached it reallocates L to 1.2 times everything allocated, holes included, and only then packs.  On
// city10000 that tripled the storage, and the fresh pages cost single updates 50-150 ms of page faults.  So before a
// modification that could run past the end, the columns are packed in place and the end is moved back to the last
// column: the holes are reused, and L grows (once, with headroom) only when the packed columns need it.
void IncrementalSmoother::make_room(const cholmod_sparse* C) {
  // What the modification can claim at the end: every column j on its paths may move there, and CHOLMOD gives a
  // moved column grow1 x its new count + grow2, at most n - j (cholmod_reallocate_column).  Its new pattern is its
  // old one, the rows of C on its path, and the new rows of its child on the path (Davis and Hager 2001); while the
  // elimination tree keeps its shape those are rows of C, so it gains at most the R distinct rows of C.  That is an
  // estimate, not a bound (a new parent brings its child's old rows); when it falls short CHOLMOD grows L itself,
  // which is right, only slower.  Measured on city10000, sphere2500 and M3500: no update used more than the estimate
  // (bench/RESULTS.md, session 6); the former 2 Lnz + 16 made city10000 grow L 55 times by more than 5 ms each.
  const int* Ci = static_cast<const int*>(C->i);
  const int* Cp = static_cast<const int*>(C->p);
  const int* Lnz = static_cast<const int*>(L_->nz);
  const size_t n = L_->n;
  size_t rows = 0;
  const size_t entries = static_cast<size_t>(Cp[C->ncol]);
  for (size_t k = 0; k < entries; ++k)
    if (!on_path_[static_cast<size_t>(Ci[k])]) on_path_[static_cast<size_t>(Ci[k])] = 1, ++rows;
  for (size_t k = 0; k < entries; ++k) on_path_[static_cast<size_t>(Ci[k])] = 0;
  const double grow1 = std::max(1.0, common_.grow1);
  size_t need = 0;
  for (size_t k = 0; k < C->ncol; ++k)
    for (int j = Ci[Cp[k]]; j >= 0 && !on_path_[static_cast<size_t>(j)]; j = parent_of(j)) {
      on_path_[static_cast<size_t>(j)] = 1;
      const double grown = grow1 * static_cast<double>(static_cast<size_t>(Lnz[j]) + rows) + static_cast<double>(common_.grow2);
      need += std::min(static_cast<size_t>(grown) + 16, n - static_cast<size_t>(j));
    }
  for (size_t k = 0; k < C->ncol; ++k)
    for (int j = Ci[Cp[k]]; j >= 0 && on_path_[static_cast<size_t>(j)]; j = parent_of(j)) on_path_[static_cast<size_t>(j)] = 0;
  int* Lp = static_cast<int*>(L_->p);
  if (static_cast<size_t>(Lp[n]) + need <= L_->nzmax) return;
  if (!cholmod_pack_factor(L_, &common_)) throw std::runtime_error("CHOLMOD could not pack the factor");
  // The end of the storage (Lp[n]) is left where it was by the packing; the last column in storage order keeps
  // what it uses plus grow2, as packing gives every column.
  const int last = static_cast<const int*>(L_->prev)[n];
  Lp[n] = Lp[last] + static_cast<int>(std::min(static_cast<size_t>(Lnz[last]) + common_.grow2, n - static_cast<size_t>(last)));
  const size_t end = static_cast<size_t>(Lp[n]);
  if (end + need > L_->nzmax && !cholmod_reallocate_factor(end + need + end / 2, L_, &common_))
    throw std::runtime_error("CHOLMOD could not grow the factor");
}

int IncrementalSmoother::parent_of(int j) const {
  // CHOLMOD keeps each column of a simplicial factor sorted, diagonal first: the parent is the next row.
  const int* Lp = static_cast<const int*>(L_->p);
  const int* Lnz = static_cast<const int*>(L_->nz);
  return Lnz[j] > 1 ? static_cast<const int*>(L_->i)[Lp[j] + 1] : -1;
}

// Which pending variables and factors can enter the system: a factor enters when all its variables are in (or
// enter); a new variable enters when the information its entering factors give it is positive definite, so that the
// system stays positive definite (a bearing-only sighting alone, say, waits for a second one).
void IncrementalSmoother::determined(const std::vector<int>& new_vars, const std::vector<size_t>& new_factors,
                                     std::vector<char>& ready) const {
  std::vector<int> slot(graph_.variables().size(), -1);
  for (size_t k = 0; k < new_vars.size(); ++k) slot[static_cast<size_t>(new_vars[k])] = static_cast<int>(k);
  ready.assign(new_vars.size(), 1);
  for (size_t k = 0; k < new_vars.size(); ++k)
    if (graph_.variables()[static_cast<size_t>(new_vars[k])].fixed) ready[k] = 1;
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<Eigen::MatrixXd> info(new_vars.size());
    for (size_t k = 0; k < new_vars.size(); ++k) {
      const int d = graph_.variables()[static_cast<size_t>(new_vars[k])].dim();
      info[k] = Eigen::MatrixXd::Zero(d, d);
    }
    for (size_t fi : new_factors) {
      const Factor& f = *graph_.factors()[fi];
      bool ok = true;
      for (int v : f.variables()) {
        const int s = slot[static_cast<size_t>(v)];
        if (s >= 0 && !ready[static_cast<size_t>(s)]) ok = false;
        if (s < 0 && pos_[static_cast<size_t>(v)] < 0 && !graph_.variables()[static_cast<size_t>(v)].fixed) ok = false;
      }
      if (!ok) continue;
      Linearization lin = f.make_linearization(lin_);
      f.linearize(lin_, lin);
      for (size_t k = 0; k < f.variables().size(); ++k) {
        const int s = slot[static_cast<size_t>(f.variables()[k])];
        if (s >= 0) info[static_cast<size_t>(s)] += lin.jacobians[k].transpose() * f.information() * lin.jacobians[k];
      }
    }
    for (size_t k = 0; k < new_vars.size(); ++k) {
      if (!ready[k] || graph_.variables()[static_cast<size_t>(new_vars[k])].fixed) continue;
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(info[k], Eigen::EigenvaluesOnly);
      const double top = eig.eigenvalues().cwiseAbs().maxCoeff();
      if (!(eig.eigenvalues().minCoeff() > 1e-12 * std::max(top, 1e-300))) ready[k] = 0, changed = true;
    }
  }
}

double IncrementalSmoother::chi2() const {
  // Each factor's e' Omega e is kept from the last call and recomputed only for the factors of the variables whose
  // estimate a solve moved since then (and for new or pending ones): the cost follows what the updates touched.
  const auto& factors = graph_.factors();
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  factor_chi2_.resize(factors.size(), unknown);
  for (int v : moved_since_chi2_) {
    estimate_moved_[static_cast<size_t>(v)] = 0;
    for (size_t f : var_factors_[static_cast<size_t>(v)]) factor_chi2_[f] = unknown;
  }
  moved_since_chi2_.clear();
  for (size_t f : pending_factors_) factor_chi2_[f] = unknown;
  double sum = 0;
  for (size_t f = 0; f < factors.size(); ++f) {
    if (std::isnan(factor_chi2_[f])) factor_chi2_[f] = factors[f]->chi2(graph_.variables());
    sum += factor_chi2_[f];
  }
  return sum;
}

double IncrementalSmoother::robust_weight_of(size_t fi) const {
  if (kernel_width_[fi] == 0) return 1.0;
  const Factor& f = *graph_.factors()[fi];
  Eigen::VectorXd e(f.residual_dim());
  f.error(lin_, e);
  return kernel_weight(fi, e.dot(f.information() * e));
}

Eigen::MatrixXd IncrementalSmoother::marginal_covariance(int index) const {
  const int p = pos_[static_cast<size_t>(index)];
  if (L_ == nullptr || p < 0) return {};
  const int d = graph_.variables()[static_cast<size_t>(index)].dim();
  // H = L D L' (L unit lower triangular, D on L's diagonal), so the block of H^-1 at columns p..p+d-1 is
  // E' L^-T D^-1 L^-1 E = Y' D^-1 Y with Y = L^-1 E, E = [e_p .. e_p+d-1].  Column k of Y is nonzero only on the
  // path from p + k to the root of L's elimination tree (the reach of e_p+k; Gilbert 1994), and the columns of one
  // variable lie on one path, so the forward solve walks that path alone: the cost is the path's nonzeros, not
  // L's, and the newest variables (ordered last, near the root) cost a few columns however large the graph.
  const int* Lp = static_cast<const int*>(L_->p);
  const int* Li = static_cast<const int*>(L_->i);
  const int* Lnz = static_cast<const int*>(L_->nz);
  const double* Lx = static_cast<const double*>(L_->x);
  std::vector<int> path;
  for (int j = p; j != -1; j = parent_of(j)) path.push_back(j);
  for (int k = 1; k < d; ++k)  // the variable's other columns: on p's path when its block is dense (always, in L)
    if (std::find(path.begin(), path.end(), p + k) == path.end()) return {};
  std::vector<int>& slot = marginal_slot_;
  if (slot.size() < static_cast<size_t>(capacity_)) slot.assign(static_cast<size_t>(capacity_), -1);
  for (size_t r = 0; r < path.size(); ++r) slot[static_cast<size_t>(path[r])] = static_cast<int>(r);
  std::vector<double> Y(path.size() * static_cast<size_t>(d), 0.0);  // row r: Y's row at column path[r]
  const size_t ud = static_cast<size_t>(d);
  for (int k = 0; k < d; ++k) Y[static_cast<size_t>(slot[static_cast<size_t>(p + k)]) * ud + static_cast<size_t>(k)] = 1.0;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(d, d);
  bool ok = true;
  for (size_t r = 0; r < path.size(); ++r) {
    const int j = path[r];
    const double dj = Lx[Lp[j]];
    if (!(dj > 0)) ok = false;
    const double* yj = &Y[r * ud];
    for (int q = Lp[j] + 1; q < Lp[j] + Lnz[j]; ++q) {
      double* yi = &Y[static_cast<size_t>(slot[static_cast<size_t>(Li[q])]) * ud];
      for (size_t k = 0; k < ud; ++k) yi[k] -= Lx[q] * yj[k];
    }
    for (int a = 0; a < d; ++a)
      for (int b = 0; b <= a; ++b) out(a, b) += yj[a] * yj[b] / dj;
  }
  out.triangularView<Eigen::StrictlyUpper>() = out.transpose();
  for (int j : path) slot[static_cast<size_t>(j)] = -1;
  if (!ok || !out.allFinite()) return {};
  // H = sum J' W J is the Fisher information of the estimate (Omega = covariance^-1): its covariance is H^-1.
  return 0.5 * (out + out.transpose());
}

void IncrementalSmoother::solve(bool full) {
  if (L_ == nullptr || capacity_ == 0) return;
  const int* Lp = static_cast<const int*>(L_->p);
  const int* Li = static_cast<const int*>(L_->i);
  const int* Lnz = static_cast<const int*>(L_->nz);
  const double* Lx = static_cast<const double*>(L_->x);
  const double* y = static_cast<const double*>(y_->x);
  // Back-substitution L' dx = D^-1 y, from the root down (a parent's column index exceeds its children's), after
  // iSAM2's wildfire (Kaess et al. 2012, Alg. 7) at the granularity of columns: a column is recomputed when CHOLMOD
  // modified it or when a column in its structure moved by more than the threshold since that column last
  // propagated.  A column that is not recomputed cuts off its subtree: a descendant's structure above it lies in
  // its own structure (the row-subtree property of L), and no descendant of an unmodified column is modified.
  std::fill(recomputed_.begin(), recomputed_.end(), 0);
  std::fill(changed_.begin(), changed_.end(), 0);
  var_changed_.assign(graph_.variables().size(), 0);
  const double threshold = full ? -1.0 : options_.wildfire;
  for (int j = capacity_ - 1; j >= 0; --j) {
    const size_t ju = static_cast<size_t>(j);
    const int first = Lp[j] + 1, end = Lp[j] + Lnz[j], parent = parent_of(j);
    if (parent >= 0 && !recomputed_[static_cast<size_t>(parent)]) continue;
    bool need = full || dirty_[ju];
    for (int k = first; !need && k < end; ++k) need = changed_[static_cast<size_t>(Li[k])] != 0;
    if (!need) continue;
    double x = y[j] / Lx[Lp[j]];
    for (int k = first; k < end; ++k) x -= Lx[k] * dx_[Li[k]];
    recomputed_[ju] = 1;
    if (x != dx_[j] && col_var_[ju] >= 0) var_changed_[static_cast<size_t>(col_var_[ju])] = 1;
    dx_[j] = x;
    // Compared with the value its dependants last saw, so that small changes cannot accumulate unseen.
    if (std::abs(x - seen_[ju]) > threshold) changed_[ju] = 1, seen_[ju] = x;
  }
  std::fill(dirty_.begin(), dirty_.end(), 0);
  auto& vars = graph_.variables();
  if (estimate_moved_.size() < vars.size()) estimate_moved_.resize(vars.size(), 0);
  for (size_t v = 0; v < vars.size(); ++v) {
    if (!(full || var_changed_[v])) continue;
    if (!estimate_moved_[v]) estimate_moved_[v] = 1, moved_since_chi2_.push_back(static_cast<int>(v));
    vars[v] = lin_[v];
    if (pos_[v] >= 0) vars[v].retract(dx_.data() + pos_[v]);
  }
}

std::vector<int> IncrementalSmoother::moved_variables() const {
  std::vector<int> moved;
  const auto& vars = lin_;
  for (size_t v = 0; v < vars.size(); ++v) {
    const int p = pos_[v];
    if (p < 0) continue;
    for (int i = 0; i < vars[v].dim(); ++i) {
      const double step = std::abs(dx_[p + i]);
      const double limit = is_rotation_component(vars[v].kind, i) ? options_.relinearize_rotation : options_.relinearize_translation;
      if (step > limit) {
        moved.push_back(static_cast<int>(v));
        break;
      }
    }
  }
  return moved;
}

size_t IncrementalSmoother::update_limit() const {
  const size_t fraction = std::max(static_cast<size_t>(options_.min_update_factors),
                                   static_cast<size_t>(options_.update_fraction * static_cast<double>(factors_in_system_)));
  return std::min(fraction, static_cast<size_t>(std::max(options_.max_update_factors, options_.min_update_factors)));
}

bool IncrementalSmoother::relinearize(const std::vector<int>& moved, IncrementalStatus& st) {
  // Rank updates cost about the path of each factor's columns to the root of the elimination tree; past a few
  // dozen factors a rebuild is cheaper (measured on M3500: bench/RESULTS.md), and the caller rebuilds instead.
  std::vector<char> mark(graph_.factors().size(), 0);
  std::vector<size_t> factors;
  for (int v : moved)
    for (size_t f : var_factors_[static_cast<size_t>(v)])
      if (!mark[f]) mark[f] = 1, factors.push_back(f);
  if (factors.size() > update_limit()) return false;
  std::vector<Contribution> before, after;
  before.reserve(factors.size());
  after.reserve(factors.size());
  for (size_t f : factors) before.push_back(linearize(f));
  for (int v : moved) {
    lin_[static_cast<size_t>(v)].retract(dx_.data() + pos_[static_cast<size_t>(v)]);
    // dx_ must describe the same estimate at the new linearization point: its step is now 0.
    // (Its subtree's steps depend on this number, not on the estimate it stands for, so they are recomputed.)
    for (int k = 0; k < lin_[static_cast<size_t>(v)].dim(); ++k) dx_[pos_[static_cast<size_t>(v)] + k] = 0.0;
  }
  for (size_t f : factors) after.push_back(linearize(f));
  // Update with the new linearization before downdating the old one: the matrix stays positive definite throughout.
  apply(after, true, true);
  apply(before, false, true);
  st.relinearized_variables += static_cast<int>(moved.size());
  st.relinearized_factors += static_cast<int>(factors.size());
  return true;
}

IncrementalStatus IncrementalSmoother::update() {
  const auto started = std::chrono::steady_clock::now();
  ++update_calls_;
  IncrementalStatus st;
  if (!gauge_checked_ && !graph_.variables().empty()) {
    // The gauge: without a fixed variable or a prior, the first pose is held fixed (as the batch optimizer does).
    bool gauge = graph_.has_fixed_variable();
    for (const auto& f : graph_.factors())
      if (f->type() == "prior") gauge = true;
    if (!gauge)
      for (size_t v = 0; v < graph_.variables().size(); ++v)
        if (graph_.variables()[v].is_pose()) {
          graph_.variables()[v].fixed = lin_[v].fixed = true;
          break;
        }
    gauge_checked_ = true;
  }
  if (L_ == nullptr) return rebuild();
  if (reordering_ && update_calls_ >= reorder_due_ && !finish_reordering(st)) return rebuild_with(1);

  std::vector<char> ready;
  determined(pending_vars_, pending_factors_, ready);
  std::vector<int> vars_in, vars_wait;
  int new_dim = 0;
  for (size_t k = 0; k < pending_vars_.size(); ++k) {
    const int v = pending_vars_[k];
    if (!ready[k]) {
      vars_wait.push_back(v);
      continue;
    }
    vars_in.push_back(v);
    if (!graph_.variables()[static_cast<size_t>(v)].fixed) new_dim += graph_.variables()[static_cast<size_t>(v)].dim();
  }
  // The pending factors all of whose variables are in the system or entering it now.
  std::vector<char> entering_var(graph_.variables().size(), 0);
  for (int v : vars_in) entering_var[static_cast<size_t>(v)] = 1;
  std::vector<size_t> factors_in, factors_wait;
  for (size_t f : pending_factors_) {
    bool ok = true;
    for (int v : graph_.factors()[f]->variables()) {
      const size_t vi = static_cast<size_t>(v);
      if (pos_[vi] < 0 && !graph_.variables()[vi].fixed && !entering_var[vi]) ok = false;
    }
    (ok ? factors_in : factors_wait).push_back(f);
  }
  if (factors_in.size() > update_limit()) return rebuild();  // a batch of new factors: iterate as a batch solve would
  if (used_ + new_dim > reserve_end_) return rebuild_with(1);  // only room is needed

  for (int v : vars_in) {
    if (graph_.variables()[static_cast<size_t>(v)].fixed) continue;
    pos_[static_cast<size_t>(v)] = used_;
    for (int k = 0; k < graph_.variables()[static_cast<size_t>(v)].dim(); ++k) col_var_[static_cast<size_t>(used_ + k)] = v;
    used_ += graph_.variables()[static_cast<size_t>(v)].dim();
  }
  std::vector<Contribution> added;
  added.reserve(factors_in.size());
  for (size_t f : factors_in) added.push_back(linearize(f));
  apply(added, true);
  for (size_t f : factors_in) {
    weight_[f] = 1.0;
    ++factors_in_system_;
    for (int v : graph_.factors()[f]->variables()) var_factors_[static_cast<size_t>(v)].push_back(f);
  }
  // Remove the identity that held each newly used column.
  std::vector<Contribution> identities;
  for (int v : vars_in) {
    const int p = pos_[static_cast<size_t>(v)];
    if (p < 0) continue;
    Contribution id;
    const int d = graph_.variables()[static_cast<size_t>(v)].dim();
    id.Ct = Eigen::MatrixXd::Identity(d, d);
    id.grad = Eigen::VectorXd::Zero(d);
    for (int k = 0; k < d; ++k) id.cols.push_back(p + k);
    identities.push_back(std::move(id));
  }
  apply(identities, false, true);
  bool definite = true;
  const int* Lp = static_cast<const int*>(L_->p);
  const double* Lx = static_cast<const double*>(L_->x);
  for (const Contribution& id : identities)
    for (int c : id.cols)
      if (!(Lx[Lp[c]] > 0)) definite = false;
  st.new_variables = static_cast<int>(vars_in.size());
  st.new_factors = static_cast<int>(factors_in.size());
  st.deferred_variables = static_cast<int>(vars_wait.size());
  pending_vars_ = vars_wait;
  pending_factors_ = factors_wait;
  if (!definite || common_.status == CHOLMOD_NOT_POSDEF) {
    common_.status = CHOLMOD_OK;
    IncrementalStatus r = rebuild();
    r.new_variables = st.new_variables, r.new_factors = st.new_factors, r.deferred_variables = st.deferred_variables;
    return r;
  }
  const bool filled = static_cast<double>(factor_nonzeros()) > options_.refill_ratio * static_cast<double>(ordered_nnz_);
  const bool spread = options_.reorder_spread > 0 && static_cast<int>(graph_.variables().size()) > options_.reorder_spread_above;
  if (filled && !spread) {
    IncrementalStatus r = rebuild_with(1);  // the new ordering is the point: one iteration
    r.new_variables = st.new_variables, r.new_factors = st.new_factors, r.deferred_variables = st.deferred_variables;
    return r;
  }
  const bool began_reordering = !reordering_ && spread && (filled || 4 * (reserve_end_ - used_) < reserve_at_order_);
  if (began_reordering) begin_reordering();
  solve(false);
  ++st.solves;
  ++updates_;
  const bool check = options_.relinearize_skip <= 1 || updates_ % options_.relinearize_skip == 0;
  for (int pass = 0; check && pass < options_.relinearization_passes; ++pass) {
    const std::vector<int> moved = moved_variables();
    if (moved.empty()) break;
    if (!relinearize(moved, st)) {
      IncrementalStatus r = rebuild_with(1);  // relinearizing everything at the estimate is the point: one iteration
      r.new_variables = st.new_variables, r.new_factors = st.new_factors, r.deferred_variables = st.deferred_variables;
      return r;
    }
    solve(false);
    ++st.solves;
  }
  if (reordering_) {
    // What is left of reorder_slice_ms after this update's own work, and at least this update's share of what the
    // last spread reordering took (with a quarter to spare, as the graph grows), so that little is left for the
    // update that installs it: with the first rule alone, city10000's updates during a reordering (4-6 ms each, the
    // factor being at its fullest) left it nearly all, 40-70 ms.  The update that began it has paid the ordering.
    const auto now = std::chrono::steady_clock::now();
    const double own = std::chrono::duration<double, std::milli>(now - started).count();
    const int64_t left = std::max<int64_t>(1, reorder_due_ - update_calls_);
    const double share = began_reordering ? 0.0 : std::max(0.0, 1.25 * reorder_work_ms_ - reorder_spent_ms_) / static_cast<double>(left);
    const auto deadline = now + std::chrono::duration<double, std::milli>(std::max(options_.reorder_slice_ms - own, share));
    advance(*reordering_, [&] { return std::chrono::steady_clock::now() >= deadline; });
    reorder_spent_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - now).count();
  }
  return st;
}

IncrementalStatus IncrementalSmoother::rebuild() { return rebuild_with(options_.rebuild_iterations); }

void IncrementalSmoother::begin_reordering() {
  std::vector<char> in(graph_.variables().size(), 0);
  for (size_t v = 0; v < pos_.size(); ++v) in[v] = pos_[v] >= 0;
  reordering_ = begin_system(in, false);
  reorder_due_ = update_calls_ + options_.reorder_spread;
  reorder_spent_ms_ = 0.0;
}

bool IncrementalSmoother::finish_reordering(IncrementalStatus& st) {
  std::unique_ptr<System> s = std::move(reordering_);
  const auto started = std::chrono::steady_clock::now();
  advance(*s, Never{});
  reorder_work_ms_ = reorder_spent_ms_ + std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  if (!s->error.empty()) return false;  // the caller rebuilds, which names the cause
  install(*s);
  st.rebuilt = true;
  ++rebuilds_;
  ++st.solves;
  return true;
}

IncrementalStatus IncrementalSmoother::rebuild_with(int iterations) {
  IncrementalStatus st;
  st.rebuilt = true;
  reordering_.reset();  // superseded
  // Everything in the system is relinearized at the current estimate (begin_system).
  for (size_t v = 0; v < lin_.size(); ++v)
    if (pos_[v] >= 0) lin_[v] = graph_.variables()[v];
  std::vector<char> ready;
  determined(pending_vars_, pending_factors_, ready);
  std::vector<int> wait;
  std::vector<char> in(graph_.variables().size(), 0);
  for (size_t v = 0; v < pos_.size(); ++v) in[v] = pos_[v] >= 0 || graph_.variables()[v].fixed;
  for (size_t k = 0; k < pending_vars_.size(); ++k) {
    if (ready[k]) {
      in[static_cast<size_t>(pending_vars_[k])] = 1;
      ++st.new_variables;
    } else {
      wait.push_back(pending_vars_[k]);
    }
  }
  std::vector<size_t> factors_wait;
  for (size_t f : pending_factors_) {
    bool ok = true;
    for (int v : graph_.factors()[f]->variables()) ok = ok && in[static_cast<size_t>(v)];
    if (ok) {
      weight_[f] = 1.0, ++st.new_factors, ++factors_in_system_;
      for (int v : graph_.factors()[f]->variables()) var_factors_[static_cast<size_t>(v)].push_back(f);
    } else {
      factors_wait.push_back(f);
    }
  }
  pending_vars_ = wait;
  pending_factors_ = factors_wait;
  st.deferred_variables = static_cast<int>(wait.size());

  ++rebuilds_;
  for (int it = 0; it < std::max(1, iterations); ++it) {
    if (it > 0 && moved_variables().empty()) break;
    // The old factor goes first: the new one then reuses its memory instead of faulting in fresh pages (M3500: peak
    // RSS 34.4 MB with both alive, 30.5 before System).
    if (L_) cholmod_free_factor(&L_, &common_);
    if (y_) cholmod_free_dense(&y_, &common_);
    // Every factor in the system linearized at the current estimate; the first iteration orders, the others keep it.
    std::unique_ptr<System> s = begin_system(in, it > 0);
    advance(*s, Never{});
    if (!s->error.empty()) {  // L_ is gone: the next update starts over
      st.ok = false;
      st.message = s->error;
      return st;
    }
    install(*s);
    ++st.solves;
  }
  return st;
}

// Positions for the free variables marked in `in`: a fill-reducing ordering of the block graph.
void IncrementalSmoother::order_blocks(const std::vector<char>& in, System& s) const {
  // Blocks: the free variables in the system, in insertion order; the newest ones are constrained to come last.
  std::vector<int> block_var, var_block(graph_.variables().size(), -1);
  for (size_t v = 0; v < in.size(); ++v)
    if (in[v] && !graph_.variables()[v].fixed) var_block[v] = static_cast<int>(block_var.size()), block_var.push_back(static_cast<int>(v));
  const size_t nb = block_var.size();
  std::vector<std::vector<int>> upper(nb);
  for (size_t b = 0; b < nb; ++b) upper[b].push_back(static_cast<int>(b));
  for (size_t f : s.factors)
    for (int u : graph_.factors()[f]->variables())
      for (int w : graph_.factors()[f]->variables()) {
        const int bu = var_block[static_cast<size_t>(u)], bw = var_block[static_cast<size_t>(w)];
        if (bu >= 0 && bw >= 0 && bu < bw) upper[static_cast<size_t>(bw)].push_back(bu);
      }
  for (auto& r : upper) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  // Hubs: landmarks (point variables), which a landmark-heavy map ties to most keyframes.  They are ordered last and
  // placed after the reserved columns, so that the keyframes added until the next ordering take columns before them.
  // Had the new keyframes come after the landmarks, every landmark's column would gain the rows of every new keyframe
  // that sees it (fill along the chain), and each sighting's rank update would walk all those columns: on a 3-D run
  // with 40 landmarks in view that cost grew with every keyframe since the last ordering.  Before them, a sighting's
  // update walks the new keyframe's column and the landmarks' dense block only.
  std::vector<char> hub(nb, 0);
  for (size_t b = 0; b < nb; ++b) hub[b] = !graph_.variables()[static_cast<size_t>(block_var[b])].is_pose();
  std::vector<int> order;
  if (static_cast<int>(nb) > options_.nested_dissection_above) {
    order = block_nested_dissection_order(upper, common_);
    std::stable_partition(order.begin(), order.end(), [&](int b) { return !hub[static_cast<size_t>(b)]; });
  } else {
    size_t poses = 0;
    for (size_t b = 0; b < nb; ++b) poses += hub[b] ? 0 : 1;
    const size_t newest = std::min<size_t>(poses / 10, 100);
    std::vector<int> group(nb, 0);
    for (size_t b = nb, seen = 0; b-- > 0 && seen < newest;)
      if (!hub[b]) group[b] = 1, ++seen;
    bool any_hub = false;
    for (size_t b = 0; b < nb; ++b)
      if (hub[b]) group[b] = 2, any_hub = true;
    order = block_amd_order(upper, common_, newest > 0 || any_hub ? &group : nullptr);
  }
  s.pos.assign(graph_.variables().size(), -1);
  s.used = 0;
  int hub_dim = 0;
  for (int b : order) {
    const size_t v = static_cast<size_t>(block_var[static_cast<size_t>(b)]);
    if (hub[static_cast<size_t>(b)]) {
      hub_dim += graph_.variables()[v].dim();
      continue;
    }
    s.pos[v] = s.used;
    s.used += graph_.variables()[v].dim();
  }
  s.reserve_end = s.used + std::max(64, static_cast<int>(options_.capacity_growth * (s.used + hub_dim)));
  s.capacity = s.reserve_end;
  for (int b : order) {
    const size_t v = static_cast<size_t>(block_var[static_cast<size_t>(b)]);
    if (!hub[static_cast<size_t>(b)]) continue;
    s.pos[v] = s.capacity;
    s.capacity += graph_.variables()[v].dim();
  }
  s.col_var.assign(static_cast<size_t>(s.capacity), -1);
  for (size_t v = 0; v < s.pos.size(); ++v)
    for (int k = 0; s.pos[v] >= 0 && k < graph_.variables()[v].dim(); ++k) s.col_var[static_cast<size_t>(s.pos[v] + k)] = static_cast<int>(v);
}

// The system of every factor now in the system, at the current estimates, ordered afresh or in the current order.
std::unique_ptr<IncrementalSmoother::System> IncrementalSmoother::begin_system(const std::vector<char>& in,
                                                                               bool keep_ordering) const {
  auto s = std::make_unique<System>(&common_);
  s->lin = graph_.variables();
  for (size_t f = 0; f < weight_.size(); ++f)
    if (weight_[f] > 0) s->factors.push_back(f);
  if (keep_ordering) {
    s->pos = pos_, s->col_var = col_var_, s->used = used_, s->reserve_end = reserve_end_, s->capacity = capacity_;
  } else {
    order_blocks(in, *s);
  }
  assemble_pattern(*s);
  return s;
}

// H's pattern (upper triangle, by column position, an identity on the reserved columns), written straight into
// compressed columns: it is known from which variables share a factor, so there is no triplet list to sort and sum
// (on city10000 that conversion alone took as long as linearizing).
void IncrementalSmoother::assemble_pattern(System& s) const {
  const auto& vars = graph_.variables();
  const auto& factors = graph_.factors();
  const size_t nv = vars.size();
  s.first.assign(nv + 1, 0);
  s.count.assign(nv, 0);
  auto each_pair = [&](auto&& visit) {
    for (size_t f : s.factors)
      for (int a : factors[f]->variables())
        for (int b : factors[f]->variables())
          if (s.pos[static_cast<size_t>(a)] >= 0 && s.pos[static_cast<size_t>(a)] < s.pos[static_cast<size_t>(b)]) visit(a, b);
  };
  each_pair([&](int, int b) { ++s.first[static_cast<size_t>(b) + 1]; });
  for (size_t v = 0; v < nv; ++v) s.first[v + 1] += s.first[v];
  s.before.assign(static_cast<size_t>(s.first[nv]), 0);
  each_pair([&](int a, int b) { s.before[static_cast<size_t>(s.first[static_cast<size_t>(b)] + s.count[static_cast<size_t>(b)]++)] = a; });
  size_t nnz = static_cast<size_t>(s.reserve_end - s.used);
  for (size_t v = 0; v < nv; ++v) {
    int* r = s.before.data() + s.first[v];
    std::sort(r, r + s.count[v], [&](int a, int b) { return s.pos[static_cast<size_t>(a)] < s.pos[static_cast<size_t>(b)]; });
    s.count[v] = static_cast<int>(std::unique(r, r + s.count[v]) - r);
    if (s.pos[v] < 0) continue;
    size_t above = 0;
    for (int k = 0; k < s.count[v]; ++k) above += static_cast<size_t>(vars[static_cast<size_t>(r[k])].dim());
    const size_t d = static_cast<size_t>(vars[v].dim());
    nnz += d * above + d * (d + 1) / 2;
  }
  s.H = cholmod_allocate_sparse(static_cast<size_t>(s.capacity), static_cast<size_t>(s.capacity), nnz, 1, 1, 1,
                                CHOLMOD_REAL, &common_);
  if (s.H == nullptr) throw std::runtime_error("CHOLMOD could not allocate the normal equations");
  int* Hp = static_cast<int*>(s.H->p);
  int* Hi = static_cast<int*>(s.H->i);
  double* Hx = static_cast<double*>(s.H->x);
  std::fill(Hx, Hx + nnz, 0.0);
  size_t at = 0;
  for (int c = 0; c < s.capacity; ++c) {
    Hp[c] = static_cast<int>(at);
    if (c >= s.used && c < s.reserve_end) {
      Hi[at] = c, Hx[at] = 1.0, ++at;
      continue;
    }
    const size_t v = static_cast<size_t>(s.col_var[static_cast<size_t>(c)]);  // a variable's columns are filled
    const int d = vars[v].dim();                                              // together, at its first one
    for (int k = 0; k < d; ++k) {
      Hp[c + k] = static_cast<int>(at);
      for (int j = s.first[v]; j < s.first[v] + s.count[v]; ++j) {
        const size_t u = static_cast<size_t>(s.before[static_cast<size_t>(j)]);
        for (int i = 0; i < vars[u].dim(); ++i) Hi[at++] = s.pos[u] + i;
      }
      for (int i = 0; i <= k; ++i) Hi[at++] = c + i;
    }
    c += d - 1;
  }
  Hp[s.capacity] = static_cast<int>(at);
  s.g = Eigen::VectorXd::Zero(s.capacity);
}

void IncrementalSmoother::assemble_values(System& s, size_t end) const {
  const auto& vars = graph_.variables();
  const auto& factors = graph_.factors();
  const int* Hp = static_cast<const int*>(s.H->p);
  double* Hx = static_cast<double*>(s.H->x);
  // Block (a, b), pos a <= pos b, of a factor: J_a' W J_b added at a's rows in b's columns.
  auto offset_in_column = [&](int a, int b) {
    int off = 0;
    for (int j = s.first[static_cast<size_t>(b)]; j < s.first[static_cast<size_t>(b)] + s.count[static_cast<size_t>(b)]; ++j) {
      const int u = s.before[static_cast<size_t>(j)];
      if (u == a) return off;
      off += vars[static_cast<size_t>(u)].dim();
    }
    return off;  // a == b: its own block follows all the others
  };
  // Buffers reused from factor to factor (the linearization while the shapes repeat): a rebuild linearizes every
  // factor, and per-factor allocations were a third of its assembly time.
  Linearization lin;
  Eigen::VectorXd We;
  Eigen::MatrixXd JaW, block;
  for (; s.assembled < end; ++s.assembled) {
    const size_t f = s.factors[s.assembled];
    const Factor& fac = *factors[f];
    const auto& fv = fac.variables();
    bool same_shape = lin.error.size() == fac.residual_dim() && lin.jacobians.size() == fv.size();
    for (size_t k = 0; same_shape && k < fv.size(); ++k)
      same_shape = lin.jacobians[k].cols() == vars[static_cast<size_t>(fv[k])].dim();
    if (!same_shape) lin = fac.make_linearization(s.lin);
    fac.linearize(s.lin, lin);
    We.noalias() = fac.information() * lin.error;
    const double w = kernel_weight(f, lin.error.dot(We));
    We *= w;
    for (size_t ka = 0; ka < fv.size(); ++ka) {
      const int pa = s.pos[static_cast<size_t>(fv[ka])];
      if (pa < 0) continue;
      const Eigen::MatrixXd& Ja = lin.jacobians[ka];
      s.g.segment(pa, Ja.cols()).noalias() += Ja.transpose() * We;
      JaW.noalias() = w * (Ja.transpose() * fac.information());
      for (size_t kb = 0; kb < fv.size(); ++kb) {
        const int pb = s.pos[static_cast<size_t>(fv[kb])];
        if (pb < pa) continue;
        block.noalias() = JaW * lin.jacobians[kb];
        const int off = offset_in_column(fv[ka], fv[kb]);
        for (int k = 0; k < block.cols(); ++k) {
          double* col = Hx + Hp[pb + k] + off;
          const int rows = pa == pb ? k + 1 : static_cast<int>(block.rows());
          for (int i = 0; i < rows; ++i) col[i] += block(i, k);
        }
      }
    }
  }
}

// The positions are the ordering, so CHOLMOD analyzes and factorizes in the natural order.  The factorization is
// up-looking, row by row (cholmod_rowfac): rows [0, k) of L depend only on rows [0, k) of H, so it stops and resumes
// at any row, and the slices give the factor one call would.
template <class Deadline>
bool IncrementalSmoother::advance(System& s, const Deadline& deadline) {
  constexpr size_t kFactorsPerSlice = 512;  // between looks at the clock: well under a millisecond each
  constexpr size_t kRowsPerSlice = 96;
  const size_t n = static_cast<size_t>(s.capacity);
  auto fail = [&](std::string why) {
    s.error = std::move(why);
    s.done = true;
    common_.status = CHOLMOD_OK;
    return true;
  };
  while (!s.done) {
    if (deadline()) return false;
    if (s.assembled < s.factors.size()) {
      assemble_values(s, std::min(s.assembled + kFactorsPerSlice, s.factors.size()));
    } else if (s.L == nullptr) {
      common_.nmethods = 1;
      common_.method[0].ordering = CHOLMOD_NATURAL;
      common_.postorder = 0;
      common_.supernodal = CHOLMOD_SIMPLICIAL;  // measured: the supernodal factor stores its relaxed
      // supernodes' zeros, which every later update and solve pays for, and ATLAS is slow on the small supernodes
      common_.final_ll = 0;
      common_.quick_return_if_not_posdef = 1;
      s.L = cholmod_analyze(s.H, &common_);
      if (s.L == nullptr) return fail("CHOLMOD symbolic analysis failed");
    } else if (s.factorized < n) {
      // Sliced only when a deadline can stop it: each call costs a pass over CHOLMOD's workspace.
      const size_t end = std::is_same_v<Deadline, Never> ? n : std::min(s.factorized + kRowsPerSlice, n);
      double beta[2] = {0.0, 0.0};
      // As cholmod_factorize does: the first call turns the symbolic factor into a numeric one with exactly the
      // space the column counts need (grow2 = 0); later updates grow it through make_room.
      const size_t grow2 = common_.grow2;
      if (s.factorized == 0) s.L->is_ll = 0, common_.grow2 = 0;
      const int ok = cholmod_rowfac(s.H, nullptr, beta, s.factorized, end, s.L, &common_);
      common_.grow2 = grow2;
      if (!ok || common_.status == CHOLMOD_NOT_POSDEF || s.L->minor < s.L->n) {
        const size_t col = s.L->minor < s.L->n ? s.L->minor : s.factorized;
        const int var = col < s.col_var.size() ? s.col_var[col] : -1;
        return fail("the normal equations are not positive definite: variable " +
                    (var >= 0 ? std::to_string(graph_.variables()[static_cast<size_t>(var)].id) : std::string("?")) +
                    " is not determined by the factors (under-constrained, or disconnected from the gauge)");
      }
      s.factorized = end;
    } else {
      cholmod_free_sparse(&s.H, &common_);
      if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, s.L, &common_))  // LDL', packed, monotonic
        return fail("CHOLMOD could not convert the factor to LDL' form");
      // y = L^-1 b, b = -g: the forward half of the solve, kept current by every later update (cholmod_updown_solve).
      cholmod_dense* b = cholmod_zeros(n, 1, CHOLMOD_REAL, &common_);
      if (b == nullptr) return fail("CHOLMOD could not allocate the right-hand side");
      for (size_t i = 0; i < n; ++i) static_cast<double*>(b->x)[i] = -s.g[static_cast<Eigen::Index>(i)];
      s.y = cholmod_solve(CHOLMOD_L, s.L, b, &common_);
      cholmod_free_dense(&b, &common_);
      if (s.y == nullptr) return fail("CHOLMOD's forward solve failed");
      s.done = true;
    }
  }
  return true;
}

// The new system replaces the current one.  Factors that entered the current system after `s` was begun are not in
// `s`: they, and the variables that entered with them, become pending again and enter `s` by rank updates in the
// update that installed it (their variables' linearization point is their current estimate).
void IncrementalSmoother::install(System& s) {
  const size_t nv = graph_.variables().size();
  std::vector<char> in_s(graph_.factors().size(), 0);
  for (size_t f : s.factors) in_s[f] = 1;
  std::vector<size_t> later_factors;
  for (size_t f = 0; f < weight_.size(); ++f)
    if (weight_[f] > 0 && !in_s[f]) later_factors.push_back(f), weight_[f] = 0.0;
  if (!later_factors.empty()) {
    later_factors.insert(later_factors.end(), pending_factors_.begin(), pending_factors_.end());
    std::sort(later_factors.begin(), later_factors.end());
    pending_factors_ = std::move(later_factors);
  }
  std::vector<int> later_vars;
  for (size_t v = 0; v < nv; ++v) {
    const bool in_new = v < s.pos.size() && s.pos[v] >= 0;
    if (in_new) {
      lin_[v] = s.lin[v];
    } else if (pos_[v] >= 0) {
      later_vars.push_back(static_cast<int>(v));
      lin_[v] = graph_.variables()[v];
    }
  }
  if (!later_vars.empty()) {
    later_vars.insert(later_vars.end(), pending_vars_.begin(), pending_vars_.end());
    std::sort(later_vars.begin(), later_vars.end());
    pending_vars_ = std::move(later_vars);
  }
  pos_ = s.pos;
  pos_.resize(nv, -1);
  col_var_ = std::move(s.col_var);
  used_ = s.used;
  reserve_end_ = s.reserve_end;
  capacity_ = s.capacity;
  for (auto& fs : var_factors_) fs.clear();
  for (size_t f : s.factors)
    for (int v : graph_.factors()[f]->variables()) var_factors_[static_cast<size_t>(v)].push_back(f);
  factors_in_system_ = s.factors.size();

  // A spread reordering replaces a factor that grew since its ordering; the new one is packed, and would grow
  // again at the next updates into fresh pages (on city10000, 30-65 ms of page faults per growth).  So it takes the
  // old one's storage size at once, while that memory has just been freed.  (A synchronous rebuild has freed the old
  // factor before building the new one, which then reuses its memory: nothing to do.)
  const size_t storage = L_ ? L_->nzmax : 0;
  if (L_) cholmod_free_factor(&L_, &common_);
  if (y_) cholmod_free_dense(&y_, &common_);
  if (delta_b_) cholmod_free_dense(&delta_b_, &common_);
  L_ = s.L, s.L = nullptr;
  if (storage > L_->nzmax && !cholmod_reallocate_factor(storage, L_, &common_))
    throw std::runtime_error("CHOLMOD could not grow the factor");
  y_ = s.y, s.y = nullptr;
  g_ = std::move(s.g);
  delta_b_ = cholmod_zeros(static_cast<size_t>(capacity_), 1, CHOLMOD_REAL, &common_);
  if (delta_b_ == nullptr) throw std::runtime_error("CHOLMOD could not allocate the update's right-hand side");
  dx_ = Eigen::VectorXd::Zero(capacity_);
  dirty_.assign(static_cast<size_t>(capacity_), 0);
  seen_.assign(static_cast<size_t>(capacity_), 0.0);
  recomputed_.assign(static_cast<size_t>(capacity_), 0);
  on_path_.assign(static_cast<size_t>(capacity_), 0);
  changed_.assign(static_cast<size_t>(capacity_), 0);
  ordered_nnz_ = factor_nonzeros();
  reserve_at_order_ = reserve_end_ - used_;
  solve(true);
}

}  // namespace sextant::graph
