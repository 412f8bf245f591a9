#include "estimators/graph/sparse_normal_equations.hpp"

#include "estimators/graph/block_ordering.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace sextant::graph {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

SparseNormalEquations::SparseNormalEquations(const FactorGraph& graph, Ordering ordering) : graph_(graph) {
  cholmod_start(&common_);
  try {  // a constructor that throws runs no destructor: what CHOLMOD holds so far is released here
    number_blocks();
    BlockPattern rows = block_pattern();
    if (ordering == Ordering::kBlockAmd) {
      renumber_blocks(block_amd_order(rows, common_));
      rows = block_pattern();
    }
    std::vector<int> colptr(static_cast<size_t>(n_) + 1, 0), rowind;
    lay_out_columns(rows, colptr, rowind);
    map_factor_pairs(rows);
    start_cholmod(ordering, colptr, rowind);
    analyze(ordering);
  } catch (...) {
    release_cholmod();
    throw;
  }
}

// One block of unknowns per variable that is not fixed, in the variables' order: offsets and dimensions.
void SparseNormalEquations::number_blocks() {
  const auto& vars = graph_.variables();
  const size_t nv = vars.size();
  offset_.assign(nv, -1);
  dim_.resize(nv);
  var_block_.assign(nv, -1);
  for (size_t i = 0; i < nv; ++i) {
    dim_[i] = vars[i].dim();
    if (vars[i].fixed) continue;
    var_block_[i] = static_cast<int>(block_var_.size());
    block_var_.push_back(static_cast<int>(i));
  }
  renumber_blocks({});
}

// Blocks (and their unknowns) numbered in `order` (position -> block; empty: as they are), offsets consecutive.
void SparseNormalEquations::renumber_blocks(const std::vector<int>& order) {
  if (!order.empty()) {
    std::vector<int> block_var(order.size());
    for (size_t k = 0; k < order.size(); ++k) block_var[k] = block_var_[static_cast<size_t>(order[k])];
    block_var_ = std::move(block_var);
  }
  n_ = 0;
  for (size_t b = 0; b < block_var_.size(); ++b) {
    const size_t v = static_cast<size_t>(block_var_[b]);
    var_block_[v] = static_cast<int>(b);
    offset_[v] = n_;
    n_ += dim_[v];
  }
}

// Rows (block indices <= column block) present in each block column, sorted; every block has its diagonal.
SparseNormalEquations::BlockPattern SparseNormalEquations::block_pattern() const {
  const size_t nb = block_var_.size();
  BlockPattern rows(nb);
  for (size_t b = 0; b < nb; ++b) rows[b].push_back(static_cast<int>(b));
  for (const auto& f : graph_.factors())
    for (int u : f->variables())
      for (int v : f->variables()) {
        const int bu = var_block_[static_cast<size_t>(u)], bv = var_block_[static_cast<size_t>(v)];
        if (bu >= 0 && bv >= 0 && bu < bv) rows[static_cast<size_t>(bv)].push_back(bu);
      }
  for (auto& r : rows) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  return rows;
}

// Compressed columns of the upper triangle (colptr, rowind), each block pair's column starts and the diagonal's
// positions.  The pairs of block column b are numbered consecutively from first_pair_[b], in the order of rows[b].
void SparseNormalEquations::lay_out_columns(const BlockPattern& rows, std::vector<int>& colptr,
                                            std::vector<int>& rowind) {
  const size_t nb = block_var_.size();
  first_pair_.assign(nb + 1, 0);
  for (size_t b = 0; b < nb; ++b) first_pair_[b + 1] = first_pair_[b] + static_cast<int>(rows[b].size());
  pair_col_start_.assign(static_cast<size_t>(first_pair_[nb]), {});
  for (size_t b = 0; b < nb; ++b) {
    const int db = dim_[static_cast<size_t>(block_var_[b])];
    const int ob = offset_[static_cast<size_t>(block_var_[b])];
    for (size_t q = 0; q < rows[b].size(); ++q)
      pair_col_start_[static_cast<size_t>(first_pair_[b]) + q].resize(static_cast<size_t>(db));
    for (int k = 0; k < db; ++k) {
      colptr[static_cast<size_t>(ob + k)] = static_cast<int>(rowind.size());
      for (size_t q = 0; q < rows[b].size(); ++q) {
        const int a = rows[b][q];
        const int va = block_var_[static_cast<size_t>(a)];
        const int oa = offset_[static_cast<size_t>(va)], da = dim_[static_cast<size_t>(va)];
        pair_col_start_[static_cast<size_t>(first_pair_[b]) + q][static_cast<size_t>(k)] =
            static_cast<int>(rowind.size());
        const int nrows = static_cast<size_t>(a) == b ? k + 1 : da;
        for (int r = 0; r < nrows; ++r) rowind.push_back(oa + r);
        if (static_cast<size_t>(a) == b) diag_pos_.push_back(static_cast<int>(rowind.size()) - 1);
      }
    }
  }
  colptr[static_cast<size_t>(n_)] = static_cast<int>(rowind.size());
  // diag_pos_ was filled in column order, which is also the order of the unknowns.
}

// Per factor, the block pair of each (u, v) of its variables (u <= v), or -1 when a variable is fixed.
void SparseNormalEquations::map_factor_pairs(const BlockPattern& rows) {
  factor_pairs_.resize(graph_.factors().size());
  for (size_t fi = 0; fi < graph_.factors().size(); ++fi) {
    const auto& fv = graph_.factors()[fi]->variables();
    for (size_t i = 0; i < fv.size(); ++i)
      for (size_t j = 0; j < fv.size(); ++j) {
        const int bu = var_block_[static_cast<size_t>(fv[i])], bv = var_block_[static_cast<size_t>(fv[j])];
        if (bu < 0 || bv < 0 || bu > bv) {
          factor_pairs_[fi].push_back(-1);
          continue;
        }
        const auto& r = rows[static_cast<size_t>(bv)];
        factor_pairs_[fi].push_back(first_pair_[static_cast<size_t>(bv)] +
                                    static_cast<int>(std::lower_bound(r.begin(), r.end(), bu) - r.begin()));
      }
  }
}

// CHOLMOD with the ordering asked for, H's pattern allocated (values zero), b zero.
void SparseNormalEquations::start_cholmod(Ordering ordering, const std::vector<int>& colptr,
                                          const std::vector<int>& rowind) {
  // Supernodal (dense BLAS on supernodes) where the factor is dense enough to pay (3-D graphs, big 2-D ones),
  // simplicial otherwise: CHOLMOD's own choice (flops / nnz(L) >= 40).  A small planar graph's factor spent more in
  // BLAS calls on tiny supernodes (and in waking the BLAS threads) than in arithmetic.  Simplicial is LL' too
  // (final_ll), so a matrix that is not positive definite fails the same way in both.
  common_.supernodal = CHOLMOD_AUTO;
  common_.final_ll = 1;
  common_.print = 0;
  switch (ordering) {
    case Ordering::kBlockAmd:
      break;
    case Ordering::kAmd:
      common_.nmethods = 1, common_.method[0].ordering = CHOLMOD_AMD;
      break;
    case Ordering::kColamd:
      common_.nmethods = 1, common_.method[0].ordering = CHOLMOD_COLAMD;
      break;
    case Ordering::kMetis:
      common_.nmethods = 1, common_.method[0].ordering = CHOLMOD_METIS;
      break;
    case Ordering::kAuto:
      break;
  }
  H_ = cholmod_allocate_sparse(static_cast<size_t>(n_), static_cast<size_t>(n_), rowind.size(), 1, 1, 1, CHOLMOD_REAL,
                               &common_);
  if (H_ == nullptr) throw std::runtime_error("CHOLMOD could not allocate the normal equations");
  std::copy(colptr.begin(), colptr.end(), static_cast<int*>(H_->p));
  std::copy(rowind.begin(), rowind.end(), static_cast<int*>(H_->i));
  values_.assign(rowind.size(), 0.0);
  b_ = Eigen::VectorXd::Zero(n_);
}

// The symbolic analysis.  With kBlockAmd the unknowns are already numbered in the block AMD order (AMD's order is
// a postorder of its assembly tree), so H is factored as numbered: CHOLMOD then factors H itself, where a permuted
// simplicial factorization first builds two transposed copies of H (for every factorization).  Else CHOLMOD's own
// ordering of the scalar pattern.
void SparseNormalEquations::analyze(Ordering ordering) {
  if (n_ == 0) return;
  if (ordering == Ordering::kBlockAmd) {
    common_.nmethods = 1;
    common_.method[0].ordering = CHOLMOD_NATURAL;
    common_.postorder = 0;
  }
  L_ = cholmod_analyze(H_, &common_);
  if (L_ == nullptr) throw std::runtime_error("CHOLMOD symbolic analysis failed");
}

SparseNormalEquations::~SparseNormalEquations() { release_cholmod(); }

void SparseNormalEquations::release_cholmod() {
  if (L_) cholmod_free_factor(&L_, &common_);
  if (H_) cholmod_free_sparse(&H_, &common_);
  cholmod_finish(&common_);
}

void SparseNormalEquations::clear() {
  std::fill(values_.begin(), values_.end(), 0.0);
  b_.setZero();
}

int SparseNormalEquations::position(int pair, int col, int row) const {
  return pair_col_start_[static_cast<size_t>(pair)][static_cast<size_t>(col)] + row;
}

template <typename Block>
void SparseNormalEquations::scatter(int pair, bool same_block, const Eigen::MatrixBase<Block>& M) {
  for (int k = 0; k < M.cols(); ++k) {
    const int rows = same_block ? k + 1 : static_cast<int>(M.rows());
    double* col = values_.data() + position(pair, k, 0);
    for (int r = 0; r < rows; ++r) col[r] += M(r, k);
  }
}

void SparseNormalEquations::add(int factor_index, const Factor& f, const Linearization& lin, double weight) {
  // Fixed sizes for the common factors (two poses, or one: planar or 3-D): no heap allocation per factor.
  const auto& fv = f.variables();
  const int r = f.residual_dim();
  const bool square = fv.size() <= 2 && std::all_of(lin.jacobians.begin(), lin.jacobians.end(),
                                                    [r](const Eigen::MatrixXd& J) { return J.cols() == r; });
  if (square && r == 3) return add_fixed<3>(factor_index, f, lin, weight);
  if (square && r == 6) return add_fixed<6>(factor_index, f, lin, weight);
  const Eigen::MatrixXd W = weight * f.information();
  const size_t nvars = fv.size();
  // J_u' W for each free variable u (a factor may have any number of variables: the IMU factor has six).
  std::vector<Eigen::MatrixXd> JtW(nvars);
  for (size_t i = 0; i < nvars; ++i) {
    if (var_block_[static_cast<size_t>(fv[i])] < 0) continue;
    JtW[i] = lin.jacobians[i].transpose() * W;
    b_.segment(offset_[static_cast<size_t>(fv[i])], dim_[static_cast<size_t>(fv[i])]) += JtW[i] * lin.error;
  }
  const auto& pairs = factor_pairs_[static_cast<size_t>(factor_index)];
  for (size_t i = 0; i < nvars; ++i)
    for (size_t j = 0; j < nvars; ++j)
      if (const int pair = pairs[i * nvars + j]; pair >= 0)
        scatter(pair, fv[i] == fv[j], JtW[i] * lin.jacobians[j]);  // rows: block of fv[i], columns: fv[j]
}

template <int N>
void SparseNormalEquations::add_fixed(int factor_index, const Factor& f, const Linearization& lin, double weight) {
  using Square = Eigen::Matrix<double, N, N>;
  const auto& fv = f.variables();
  const size_t nvars = fv.size();
  const Square W = weight * Eigen::Map<const Square>(f.information().data());
  const Eigen::Map<const Eigen::Matrix<double, N, 1>> e(lin.error.data());
  Square JtW[2];
  for (size_t i = 0; i < nvars; ++i) {
    if (var_block_[static_cast<size_t>(fv[i])] < 0) continue;
    JtW[i] = Eigen::Map<const Square>(lin.jacobians[i].data()).transpose() * W;
    b_.segment<N>(offset_[static_cast<size_t>(fv[i])]) += JtW[i] * e;
  }
  const auto& pairs = factor_pairs_[static_cast<size_t>(factor_index)];
  for (size_t i = 0; i < nvars; ++i)
    for (size_t j = 0; j < nvars; ++j)
      if (const int pair = pairs[i * nvars + j]; pair >= 0)
        scatter(pair, fv[i] == fv[j], Square(JtW[i] * Eigen::Map<const Square>(lin.jacobians[j].data())));
}

Eigen::VectorXd SparseNormalEquations::diagonal() const {
  Eigen::VectorXd d(n_);
  for (int i = 0; i < n_; ++i) d[i] = values_[static_cast<size_t>(diag_pos_[static_cast<size_t>(i)])];
  return d;
}

bool SparseNormalEquations::solve(double lambda, Eigen::VectorXd& dx, std::string* why) {
  dx.setZero(n_);
  if (n_ == 0) return true;
  double* x = static_cast<double*>(H_->x);
  std::copy(values_.begin(), values_.end(), x);
  if (lambda > 0)
    for (int i = 0; i < n_; ++i) {
      const size_t p = static_cast<size_t>(diag_pos_[static_cast<size_t>(i)]);
      x[p] += lambda * std::max(values_[p], 1e-6);
    }
  const auto t0 = Clock::now();
  common_.quick_return_if_not_posdef = 1;
  const int ok = cholmod_factorize(H_, L_, &common_);
  factor_seconds_ += seconds_since(t0);
  if (!ok || common_.status == CHOLMOD_NOT_POSDEF || L_->minor < L_->n) {
    if (why) {
      // The column where the factorization broke down, back through the fill-reducing permutation.
      const int* perm = static_cast<const int*>(L_->Perm);
      const size_t minor = L_->minor < L_->n ? L_->minor : 0;
      const int col = perm ? perm[minor] : static_cast<int>(minor);
      int var = -1;
      for (size_t v = 0; v < offset_.size(); ++v)
        if (offset_[v] >= 0 && col >= offset_[v] && col < offset_[v] + dim_[v]) var = static_cast<int>(v);
      *why = common_.status == CHOLMOD_NOT_POSDEF || L_->minor < L_->n
                 ? "the normal equations are not positive definite: variable " +
                       (var >= 0 ? std::to_string(graph_.variables()[static_cast<size_t>(var)].id) : std::string("?")) +
                       " (tangent component " +
                       std::to_string(var >= 0 ? col - offset_[static_cast<size_t>(var)] : -1) +
                       ") is not determined by the factors (under-constrained, or disconnected from the gauge)"
                 : "CHOLMOD factorization failed (status " + std::to_string(common_.status) + ")";
    }
    return false;
  }
  const auto t1 = Clock::now();
  cholmod_dense* rhs =
      cholmod_allocate_dense(static_cast<size_t>(n_), 1, static_cast<size_t>(n_), CHOLMOD_REAL, &common_);
  double* r = static_cast<double*>(rhs->x);
  for (int i = 0; i < n_; ++i) r[i] = -b_[i];
  cholmod_dense* sol = cholmod_solve(CHOLMOD_A, L_, rhs, &common_);
  cholmod_free_dense(&rhs, &common_);
  if (sol == nullptr) {
    if (why) *why = "CHOLMOD solve failed (status " + std::to_string(common_.status) + ")";
    return false;
  }
  dx = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(sol->x), n_);
  cholmod_free_dense(&sol, &common_);
  solve_seconds_ += seconds_since(t1);
  if (!dx.allFinite()) {
    if (why) *why = "the solution of the normal equations is not finite";
    return false;
  }
  return true;
}

size_t SparseNormalEquations::nonzeros_in_factor() const {
  if (L_ == nullptr) return 0;
  return L_->is_super ? L_->xsize : L_->nzmax;
}

}  // namespace sextant::graph
