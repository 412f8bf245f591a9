#pragma once
// What the incremental smoother's steps share: the graph and its linearization points, which factors and variables
// are in the factorized system and which wait, and the factorization itself with its per-column bookkeeping.
// Internal to the smoother (incremental_smoother.hpp is the public class; its file comment says what each part does).
#include "estimators/graph/factor_graph.hpp"
#include "estimators/graph/incremental_options.hpp"
#include "estimators/graph/smoother/cholmod_handles.hpp"
#include "estimators/graph/smoother/reorder_scheduler.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace sextant::graph::smoother {

/// The current factorization H = L D L' and its solve, by column position (the ordering).  Columns [0, used) hold
/// variables; [used, reserve_end) are reserved for new variables and hold an identity until used; [reserve_end,
/// capacity) hold the hub variables, the landmarks, after the reserved columns (linear_system.cpp says why).
struct Factorization {
  FactorPtr L;
  DensePtr y;          // L^-1 (-g): the forward solve, updated with the factor
  DensePtr delta_b;    // scratch for cholmod_updown_solve (zero between calls)
  Eigen::VectorXd g;   // gradient J' W e at the linearization point
  Eigen::VectorXd dx;  // the solution
  int used = 0, reserve_end = 0, capacity = 0;
  size_t ordered_nnz = 0;        // nnz(L) right after the last ordering
  int reserve_at_order = 0;      // reserved columns right after the last ordering
  std::vector<int> col_var;      // per column: the variable, -1 for a reserved column
  std::vector<char> dirty;       // per column: modified by an update since the last solve
  std::vector<char> recomputed;  // per column, during a solve
  std::vector<char> on_path;     // per column, during make_room (all 0 between calls)
  std::vector<char> changed;     // per column, during a solve: moved past the wildfire threshold
  std::vector<double> seen;      // per column: its step when its subtree was last recomputed

  /// The parent of column j in the elimination tree of L, -1 for a root.  CHOLMOD keeps each column of a simplicial
  /// factor sorted, diagonal first: the parent is the next row.
  int parent_of(int j) const {
    const int* Lp = static_cast<const int*>(L->p);
    const int* Lnz = static_cast<const int*>(L->nz);
    return Lnz[j] > 1 ? static_cast<const int*>(L->i)[Lp[j] + 1] : -1;
  }
  size_t nonzeros() const;
};

struct SmootherState {
  explicit SmootherState(const IncrementalOptions& o) : options(o) {}

  IncrementalOptions options;
  Workspace workspace;               // declared before every CHOLMOD handle: freed after them
  FactorGraph graph;                 // estimates and factors
  std::vector<Variable> lin;         // linearization points
  std::vector<int> pos;              // per variable: first column in L (the ordering), -1: fixed or not yet in
  std::vector<double> weight;        // per factor: 1 once in the system, 0 while pending
  std::vector<double> kernel_width;  // per factor: its robust kernel's width, 0: no kernel
  std::vector<std::vector<size_t>> var_factors;  // per variable: the factors in the system that touch it
  std::vector<int> pending_vars;
  std::vector<size_t> pending_factors;
  size_t factors_in_system = 0;
  int rebuilds = 0;
  int64_t interrupted_rebuilds = 0;  // rebuilds ended at options.interrupt
  int64_t updates = 0;               // updates that solved incrementally (relinearize_skip counts these)
  int64_t update_calls = 0;          // every update(): the clock of spread reorderings and of fault injection
  bool gauge_checked = false;
  std::string cholmod_failure;  // what the last failed CHOLMOD call was (rank_update.cpp, linear_system.cpp)
  Factorization fx;
  std::vector<char> var_changed;  // per variable, after a solve: its step changed
  // chi2() caches: per factor e' Omega e at the estimate of the last call (NaN: stale); per variable whether its
  // estimate moved since, and those variables.
  std::vector<double> factor_chi2;
  std::vector<char> estimate_moved;
  std::vector<int> moved_since_chi2;
  std::vector<int> marginal_slot;  // per column, during marginal_covariance (all -1 between calls)
  ReorderScheduler reorder;

  /// The robust weight of factor `f` at e' Omega e = chi2 (1 for a factor without a kernel).
  double kernel_weight(size_t f, double chi2) const;
};

/// Whether component i of a variable of kind k is a rotation (radians) rather than a translation or point coordinate.
inline bool is_rotation_component(VariableKind k, int i) {
  return (k == VariableKind::kPose2 && i == 2) || (k == VariableKind::kPose3 && i >= 3);
}

}  // namespace sextant::graph::smoother
