#include "estimators/graph/smoother/smoother_state.hpp"

namespace sextant::graph::smoother {

size_t Factorization::nonzeros() const {
  if (L == nullptr) return 0;
  const int* nz = static_cast<const int*>(L->nz);
  size_t s = 0;
  for (size_t j = 0; j < L->n; ++j) s += static_cast<size_t>(nz[j]);
  return s;
}

double SmootherState::kernel_weight(size_t f, double chi2) const {
  return kernel_width[f] > 0 ? robust_weight(options.kernel, kernel_width[f], chi2) : 1.0;
}

}  // namespace sextant::graph::smoother
