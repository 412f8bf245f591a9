#include "estimators/graph/factor_graph.hpp"

#include <stdexcept>
#include <string>

namespace sextant::graph {

int FactorGraph::add_variable(const Variable& v) {
  if (index_.count(v.id)) throw std::invalid_argument("variable " + std::to_string(v.id) + " added twice");
  const int i = static_cast<int>(variables_.size());
  variables_.push_back(v);
  index_[v.id] = i;
  return i;
}

int FactorGraph::index_of(int64_t id) const {
  auto it = index_.find(id);
  return it == index_.end() ? -1 : it->second;
}

void FactorGraph::add_factor(std::unique_ptr<Factor> f) { factors_.push_back(std::move(f)); }

double FactorGraph::chi2() const {
  double s = 0;
  Eigen::VectorXd e, weighted;
  for (const auto& f : factors_) s += f->chi2(variables_, e, weighted);
  return s;
}

bool FactorGraph::has_fixed_variable() const {
  for (const auto& v : variables_)
    if (v.fixed) return true;
  return false;
}

bool FactorGraph::has_gauge() const {
  if (has_fixed_variable()) return true;
  for (const auto& f : factors_)
    if (f->fixes_gauge()) return true;
  return false;
}

}  // namespace sextant::graph
