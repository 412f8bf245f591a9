#pragma once
// The incremental smoother's linear system: the Gauss-Newton normal equations H dx = -g of the factors in the
// system at a linearization point, in a fill-reducing block ordering, factorized H = L D L' (simplicial LDL', the
// form CHOLMOD's rank updates modify), with the forward half of the solve y = L^-1 (-g).
//   begin_system   which factors, at which linearization point, in which columns (a constrained-AMD or
//                  nested-dissection block ordering, block_ordering.hpp), and H's pattern (system_assembly.cpp);
//   advance        assembly of H's values, symbolic analysis and numeric factorization, in slices that stop at a
//                  deadline and resume (sliced_factorization.cpp): the slices give exactly the factor one call would;
//   install        the system becomes the smoother's current one.
#include "estimators/graph/incremental_options.hpp"
#include "estimators/graph/smoother/cholmod_handles.hpp"
#include "estimators/graph/variable.hpp"

#include <Eigen/Core>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace sextant::graph::smoother {

struct SmootherState;

/// A linearized system being built: which factors, at which linearization point, in which column positions, and
/// its normal equations and factor as far as they got.
struct System {
  std::vector<size_t> factors;  // the factors in the system, ascending
  std::vector<Variable> lin;    // the linearization point: every variable's estimate when the system was begun
  std::vector<int> pos;         // per variable: first column, -1 when not in the system
  std::vector<int> col_var;     // per column: the variable, -1 for a reserved column
  int used = 0, reserve_end = 0, capacity = 0;  // as Factorization's (smoother_state.hpp)
  // H's column pattern by variable: the variables before it in the ordering that share a factor with it, by position
  // (flat: before[first[v] .. first[v] + count[v])); its own block comes last in each of its columns.
  std::vector<int> first, count, before;
  SparsePtr H;  // upper triangle; freed once factorized
  Eigen::VectorXd g;
  FactorPtr L;
  DensePtr y;             // L^-1 (-g)
  size_t assembled = 0;   // factors linearized into H and g
  size_t factorized = 0;  // rows of L computed
  // Sliced factorization (sliced_factorization.cpp): the work of rows [0, k) of L, and the work and time the
  // sliced calls have taken so far (their rate sizes the next call).
  std::vector<double> row_work;
  double sliced_work = 0.0, sliced_ms = 0.0;
  bool done = false;
  std::string error;  // why it failed (when done)
  SmootherFailure failure = SmootherFailure::kNone;
};

/// The system of every factor now in the smoother's system plus those marked by the caller's admission, at the
/// current estimates, ordered afresh (the free variables marked in `in`) or in the current order.  A CHOLMOD failure
/// leaves the system done with its error.
std::unique_ptr<System> begin_system(SmootherState& s, const std::vector<char>& in, bool keep_ordering);
/// H's pattern (upper triangle, reserved columns = identity) with zero values, and g = 0 (system_assembly.cpp).
/// False when CHOLMOD cannot allocate it.
bool assemble_pattern(SmootherState& s, System& sys);
/// Linearizes the system's factors up to `end` into H and g (system_assembly.cpp).
void assemble_values(const SmootherState& s, System& sys, size_t end);
/// Works on `sys` while `ms_left()` (the milliseconds left of this slice, read between chunks of about a
/// millisecond) is positive, or to the end when it is empty (no slicing then): assembly, symbolic analysis,
/// factorization row by row, the forward solve.  Returns true when done (sys.error says whether it failed).
/// (sliced_factorization.cpp)
bool advance(SmootherState& s, System& sys, const std::function<double()>& ms_left);
/// Makes `sys` the current system; factors and variables that entered the current one after `sys` was begun become
/// pending again.  Then solves (back_substitution.hpp).  False when CHOLMOD fails (the factorization is then dropped).
bool install(SmootherState& s, System& sys);
/// Forgets the factorization after a CHOLMOD failure (it may be half modified): the next update rebuilds it.
void drop_factorization(SmootherState& s);

}  // namespace sextant::graph::smoother
