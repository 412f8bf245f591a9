#pragma once
// The Gauss-Newton normal equations H dx = -b of a factor graph, assembled block by block straight into CHOLMOD's
// compressed-column format (upper triangle), with the sparsity pattern and CHOLMOD's symbolic analysis computed once
// per graph structure and reused for every numeric factorization.  With the default block AMD ordering the unknowns
// are numbered in that order (offset() says where each variable's block is), so H is factored as it is stored.
//   H = sum_f J_f' W_f J_f,  b = sum_f J_f' W_f e_f,  W_f = w_f Omega_f (w_f: robust weight).
// Fixed variables have no block: they are constants of the problem (the gauge).
#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/ordering.hpp"

#include <cholmod.h>

#include <string>
#include <vector>

namespace sextant::graph {

class SparseNormalEquations {
 public:
  /// Builds the pattern for the graph's current structure and runs the symbolic analysis.
  SparseNormalEquations(const FactorGraph& graph, Ordering ordering = Ordering::kBlockAmd);
  ~SparseNormalEquations();
  SparseNormalEquations(const SparseNormalEquations&) = delete;
  SparseNormalEquations& operator=(const SparseNormalEquations&) = delete;

  /// Zeroes H and b.
  void clear();
  /// Adds factor `f` (index in the graph) linearized as `lin`, weighted by `weight`.
  void add(int factor_index, const Factor& f, const Linearization& lin, double weight);
  /// Solves (H + lambda diag(H)) dx = -b.  On failure returns false and says which variable is not determined.
  bool solve(double lambda, Eigen::VectorXd& dx, std::string* why);

  const Eigen::VectorXd& gradient() const { return b_; }
  /// Diagonal of H (for the LM model's predicted decrease).
  Eigen::VectorXd diagonal() const;
  int dimension() const { return n_; }
  /// Offset of variable `index` in dx, or -1 for a fixed variable.
  int offset(int variable_index) const { return offset_[static_cast<size_t>(variable_index)]; }
  double factorization_seconds() const { return factor_seconds_; }
  double solve_seconds() const { return solve_seconds_; }
  size_t nonzeros_in_factor() const;

 private:
  int position(int pair, int col_in_block, int row_in_block) const;
  // The constructor's steps.
  using BlockPattern = std::vector<std::vector<int>>;  // per block column: the block rows (<= it) present, sorted
  void number_blocks();
  void renumber_blocks(const std::vector<int>& order);
  BlockPattern block_pattern() const;
  void lay_out_columns(const BlockPattern& rows, std::vector<int>& colptr, std::vector<int>& rowind);
  void map_factor_pairs(const BlockPattern& rows);
  void start_cholmod(Ordering ordering, const std::vector<int>& colptr, const std::vector<int>& rowind);
  void analyze(Ordering ordering);
  // add() for square N x N factors on one or two variables, and the one scatter of a block into H's values.
  template <int N>
  void add_fixed(int factor_index, const Factor& f, const Linearization& lin, double weight);
  template <typename Block>
  void scatter(int pair, bool same_block, const Eigen::MatrixBase<Block>& M);

  // Frees L and H and finishes CHOLMOD's workspace (the destructor, or a constructor that throws).
  void release_cholmod();

  const FactorGraph& graph_;
  int n_ = 0;
  std::vector<int> offset_, dim_;  // per variable
  std::vector<int> block_var_;     // per block: the variable index
  std::vector<int> var_block_;     // per variable: its block, or -1
  // For each block pair (a <= b): the position in H's values of element (row 0 of a, column k of b), per k.
  std::vector<std::vector<int>> pair_col_start_;
  std::vector<int> first_pair_;                 // per block column: the index of its first pair
  std::vector<std::vector<int>> factor_pairs_;  // per factor: pair index for each (u, v) of its variables, u <= v
  std::vector<int> diag_pos_;
  cholmod_common common_{};
  cholmod_sparse* H_ = nullptr;
  cholmod_factor* L_ = nullptr;
  std::vector<double> values_;  // H's values without damping
  Eigen::VectorXd b_;
  double factor_seconds_ = 0, solve_seconds_ = 0;
};

}  // namespace sextant::graph
