// CHOLMOD's objects in RAII handles: CHOLMOD's own count of the memory in use (cholmod_common::memory_inuse) returns
// to where it was when the handles (and the workspace's arrays) go, also when a handle is moved or reset; the fault seam fails exactly once.
#include "estimators/graph/smoother/cholmod_handles.hpp"

#include <doctest/doctest.h>

#include <utility>

using namespace sextant::graph::smoother;

TEST_CASE("cholmod handles free what they own, the fault seam fails one factorization") {
  Workspace w;
  const size_t before = w->memory_inuse;
  {
    SparsePtr A = own(cholmod_speye(50, 50, CHOLMOD_REAL, w.get()), w);
    REQUIRE(A != nullptr);
    DensePtr b = own(cholmod_ones(50, 1, CHOLMOD_REAL, w.get()), w);
    REQUIRE(b != nullptr);
    A->stype = 1;  // symmetric, upper triangle: the identity is its own factor
    FactorPtr L = own(cholmod_analyze(A.get(), w.get()), w);
    REQUIRE(L != nullptr);
    REQUIRE(cholmod_factorize(A.get(), L.get(), w.get()));
    DensePtr x = own(cholmod_solve(CHOLMOD_A, L.get(), b.get(), w.get()), w);
    REQUIRE(x != nullptr);
    CHECK(static_cast<const double*>(x->x)[49] == 1.0);
    CHECK(w->memory_inuse > before);
    FactorPtr moved = std::move(L);  // the new owner frees it, once
    CHECK(L == nullptr);
    x.reset();
  }
  cholmod_free_work(w.get());  // the workspace's own arrays (grown by analyze and factorize) go too
  CHECK(w->memory_inuse == before);

  CHECK_FALSE(w.take_fault());
  w.arm_fault();
  CHECK(w.take_fault());
  CHECK(w->status == CHOLMOD_OUT_OF_MEMORY);
  CHECK_FALSE(w.take_fault());
}
