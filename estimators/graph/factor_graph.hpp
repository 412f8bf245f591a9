#pragma once
// A factor graph: variables (poses and points, addressed by the user's ids) and the factors between them.
#include "estimators/graph/factor.hpp"

#include <memory>
#include <unordered_map>
#include <vector>

namespace sextant::graph {

class FactorGraph {
 public:
  /// Adds a variable; throws std::invalid_argument when the id exists already.  Returns its index.
  int add_variable(const Variable& v);
  /// Index of the variable with user id `id`, or -1.
  int index_of(int64_t id) const;
  void add_factor(std::unique_ptr<Factor> f);

  std::vector<Variable>& variables() { return variables_; }
  const std::vector<Variable>& variables() const { return variables_; }
  const std::vector<std::unique_ptr<Factor>>& factors() const { return factors_; }

  /// chi2 = sum e' Omega e over all factors (g2o's definition).
  double chi2() const;
  bool has_fixed_variable() const;
  /// Whether the map frame is fixed: a fixed variable or a factor that fixes the gauge (a prior).  Without either, the
  /// solution is determined only up to a rigid motion of the whole map, and the solvers hold the first pose fixed.
  bool has_gauge() const;

 private:
  std::vector<Variable> variables_;
  std::unordered_map<int64_t, int> index_;
  std::vector<std::unique_ptr<Factor>> factors_;
};

}  // namespace sextant::graph
