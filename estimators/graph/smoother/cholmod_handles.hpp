#pragma once
// CHOLMOD's objects owned by RAII handles (Davis, "CHOLMOD", ACM TOMS 2008), for the incremental smoother's steps.
// Internal: only the smoother's sources include this (the public headers stay free of <cholmod.h>).
#include <cholmod.h>

#include <memory>

namespace sextant::graph::smoother {

/// CHOLMOD's settings and workspace (cholmod_common), started with its owner and finished with it.  Every handle
/// below refers to it when it frees its object, so it must outlive them (declare it before them).
///
/// It also holds the fault-injection seam of IncrementalOptions::fail_factorization_at_update: once armed, the next
/// factorization asks take_fault() instead of calling CHOLMOD, and fails as CHOLMOD does when out of memory.
class Workspace {
 public:
  Workspace() {
    cholmod_start(&common_);
    common_.print = 0;
  }
  ~Workspace() { cholmod_finish(&common_); }
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  cholmod_common* get() { return &common_; }
  cholmod_common* operator->() { return &common_; }
  const cholmod_common* operator->() const { return &common_; }
  cholmod_common& operator*() { return common_; }

  void arm_fault() { fault_armed_ = true; }
  /// True once after arm_fault(): the caller skips its CHOLMOD call and treats it as failed (status
  /// CHOLMOD_OUT_OF_MEMORY, as CHOLMOD leaves it).
  bool take_fault() {
    if (!fault_armed_) return false;
    fault_armed_ = false;
    common_.status = CHOLMOD_OUT_OF_MEMORY;
    return true;
  }

 private:
  cholmod_common common_{};
  bool fault_armed_ = false;
};

struct FreeFactor {
  cholmod_common* common = nullptr;
  void operator()(cholmod_factor* p) const { cholmod_free_factor(&p, common); }
};
struct FreeSparse {
  cholmod_common* common = nullptr;
  void operator()(cholmod_sparse* p) const { cholmod_free_sparse(&p, common); }
};
struct FreeDense {
  cholmod_common* common = nullptr;
  void operator()(cholmod_dense* p) const { cholmod_free_dense(&p, common); }
};

using FactorPtr = std::unique_ptr<cholmod_factor, FreeFactor>;
using SparsePtr = std::unique_ptr<cholmod_sparse, FreeSparse>;
using DensePtr = std::unique_ptr<cholmod_dense, FreeDense>;

inline FactorPtr own(cholmod_factor* p, Workspace& w) { return FactorPtr(p, FreeFactor{w.get()}); }
inline SparsePtr own(cholmod_sparse* p, Workspace& w) { return SparsePtr(p, FreeSparse{w.get()}); }
inline DensePtr own(cholmod_dense* p, Workspace& w) { return DensePtr(p, FreeDense{w.get()}); }

}  // namespace sextant::graph::smoother
