#include "estimators/graph/block_ordering.hpp"

#include <cholmod_camd.h>
#include <cholmod_partition.h>

#include <stdexcept>

namespace sextant::graph {

namespace {

// The symmetric block pattern (upper triangle) for CHOLMOD's orderings; the caller frees it.
cholmod_sparse* block_pattern(const std::vector<std::vector<int>>& upper_rows, cholmod_common& common) {
  const size_t nb = upper_rows.size();
  size_t nnz = 0;
  for (const auto& r : upper_rows) nnz += r.size();
  cholmod_sparse* B = cholmod_allocate_sparse(nb, nb, nnz, 1, 1, 1, CHOLMOD_PATTERN, &common);
  if (B == nullptr) throw std::runtime_error("CHOLMOD could not allocate the block pattern");
  int* p = static_cast<int*>(B->p);
  int* i = static_cast<int*>(B->i);
  size_t k = 0;
  for (size_t b = 0; b < nb; ++b) {
    p[b] = static_cast<int>(k);
    for (int a : upper_rows[b]) i[k++] = a;
  }
  p[nb] = static_cast<int>(k);
  return B;
}

}  // namespace

std::vector<int> block_amd_order(const std::vector<std::vector<int>>& upper_rows, cholmod_common& common,
                                 const std::vector<int>* group) {
  std::vector<int> order(upper_rows.size());
  if (order.empty()) return order;
  cholmod_sparse* B = block_pattern(upper_rows, common);
  int ok;
  if (group != nullptr) {
    std::vector<int> cmember(*group);
    ok = cholmod_camd(B, nullptr, 0, cmember.data(), order.data(), &common);
  } else {
    ok = cholmod_amd(B, nullptr, 0, order.data(), &common);
  }
  cholmod_free_sparse(&B, &common);
  if (!ok) throw std::runtime_error("CHOLMOD's AMD ordering of the block graph failed");
  return order;
}

std::vector<int> block_nested_dissection_order(const std::vector<std::vector<int>>& upper_rows,
                                               cholmod_common& common) {
  std::vector<int> order(upper_rows.size());
  if (order.empty()) return order;
  cholmod_sparse* B = block_pattern(upper_rows, common);
  const int ok = cholmod_metis(B, nullptr, 0, 1, order.data(), &common);
  cholmod_free_sparse(&B, &common);
  if (!ok) throw std::runtime_error("CHOLMOD's METIS ordering of the block graph failed");
  return order;
}

}  // namespace sextant::graph
