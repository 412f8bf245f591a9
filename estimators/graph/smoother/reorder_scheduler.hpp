#pragma once
// Reordering in the background of the updates: the only code of the incremental smoother that reads a clock.
//
// When the factor has filled in past refill_ratio times its size after the last ordering (or the reserved columns
// are three quarters used, or a relinearization round would change more factors than rank updates do cheaply) in a
// system of more than reorder_spread_above variables or reorder_spread_nonzeros entries of L, the current factor is
// still exact, only slower to update (or linearized further away); so the new ordering and factorization are built a slice at a time at the end of the
// next reorder_spread updates (each spends on it what is left of reorder_slice_ms after its own work, and at least
// its share of the time the previous reordering took), and the new system replaces the old one at the start of the
// update reorder_spread after the one that began it, whatever the clock said: the estimates after every update are
// the same on a fast or a slow machine (deterministic replay), only the per-update latency depends on the slices.
// The new system is linearized at the estimates of the update that began it; the factors and variables that arrived
// in between enter it as the pending ones of the replacing update (install, linear_system.hpp).
#include "estimators/graph/smoother/linear_system.hpp"

#include <chrono>
#include <cstdint>
#include <memory>

namespace sextant::graph::smoother {

class ReorderScheduler {
 public:
  /// Notes when an update began: its own work counts against its slice budget.
  void update_begins() { update_started_ = std::chrono::steady_clock::now(); }
  bool under_way() const { return system_ != nullptr; }
  /// A reordering under way is due at update() call number `update_call`.
  bool due(int64_t update_call) const { return system_ && update_call >= due_; }
  /// Begins a reordering of everything in the system at the current estimates, due reorder_spread updates later.
  void begin(SmootherState& s);
  enum class Finished { kInstalled, kFailed, kCholmodFailed };
  /// Completes the due reordering and puts it in place.  kFailed: the new system could not be factorized (the
  /// caller rebuilds, which names the cause); kCholmodFailed: CHOLMOD failed while installing it.
  Finished finish(SmootherState& s);
  /// This update's slice of the reordering under way (`began_now`: the update that began it has paid the ordering).
  void work(SmootherState& s, bool began_now);
  /// Drops a reordering under way (a rebuild supersedes it).
  void cancel() { system_.reset(); }

 private:
  std::unique_ptr<System> system_;  // the reordering under way
  int64_t due_ = 0;                 // the update() call at which it replaces the current system
  double spent_ms_ = 0.0;           // time its slices have taken so far
  double work_ms_ = 0.0;            // time the last reordering took from its first slice to its installation
  std::chrono::steady_clock::time_point update_started_{};
};

}  // namespace sextant::graph::smoother
