#pragma once
// Reordering in the background of the updates: the only code of the incremental smoother that reads a clock.
//
// When the factor has filled in past refill_ratio times its size after the last ordering (or the reserved columns
// are three quarters used, or a relinearization round would change more factors than rank updates do cheaply) in a
// system of more than reorder_spread_above variables, reorder_spread_nonzeros entries of L or reorder_spread_factors
// factors, the current factor is still exact, only slower to update (or linearized further away); so the new
// ordering and factorization are built a slice at a time at the end of the next reorder_spread updates (each spends
// on it what is left of reorder_slice_ms after its own work, and at least an even share of the work left: the
// factorization's remaining rows at the rate the last reordering's ran, remaining_ms), and the new system replaces
// the old one at the start of the update reorder_spread after the one
// that began it, whatever the clock said: the estimates after every update are the same on a fast or a slow machine
// (deterministic replay), only the per-update latency depends on the slices.
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
  bool under_way() const { return system_ != nullptr || first_build_requested_; }
  /// A reordering under way is due at update() call number `update_call`.
  bool due(int64_t update_call) const { return under_way() && update_call >= due_; }
  /// Begins a reordering of everything in the system at the current estimates, due reorder_spread updates later;
  /// `relinearizes`: begun because relinearization by rank updates would change too many factors.
  void begin(SmootherState& s, bool relinearizes = false);
  /// A reordering begun for relinearization is under way: relinearization waits for it.  The new system is
  /// linearized at the estimates of the update that began it and replaces every linearization point when it lands,
  /// so rank updates of the old factor meanwhile would be thrown away (sphere2500: a third of those updates' time;
  /// the estimates in between, solved at the older linearization, had a chi2 at most 1.6e-4 above, bench/RESULTS.md).
  /// Not for one begun for fill-in: those can follow each other closely, and would starve relinearization.
  bool relinearizing() const { return system_ != nullptr && relinearizes_; }
  /// The same for the free variables marked in `in` and the factors of weight > 0 (a first build: nothing is in the
  /// system yet).
  void begin(SmootherState& s, const std::vector<char>& in);
  /// A first build asked for (IncrementalSmoother::begin_spread_build), to be begun by the next update: under way
  /// from now on, though there is no system yet.
  void request_first_build() { first_build_requested_ = true; }
  bool first_build_requested() const { return first_build_requested_; }
  enum class Finished { kInstalled, kFailed, kCholmodFailed };
  /// Completes the due reordering and puts it in place.  kFailed: the new system could not be factorized (the
  /// caller rebuilds, which names the cause); kCholmodFailed: CHOLMOD failed while installing it.
  Finished finish(SmootherState& s);
  /// This update's slice of the reordering under way (`began_now`: the update that began it has paid the ordering).
  void work(SmootherState& s, bool began_now);
  /// Drops a reordering under way (a rebuild supersedes it).
  void cancel() { system_.reset(), first_build_requested_ = false; }
  /// Paces the slices as `other`'s last reordering ran (its time and factorization rate, remaining_ms): for a system
  /// like the one `other` holds, such as a lifelong thinning's copy of it, which has no last reordering of its own.
  /// Without it, such a smoother's first build gives every slice only what its update leaves of reorder_slice_ms, and
  /// the update that installs it factorizes the rest itself (a thinning of 8 robots' 2,650 keyframes: 75-117 ms).
  void pace_like(const ReorderScheduler& other) { work_ms_ = other.work_ms_, rate_ = other.rate_; }

 private:
  /// Milliseconds of work the reordering under way still needs, as far as can be told (reorder_scheduler.cpp).
  double remaining_ms() const;
  static constexpr double kRateAfterMs = 5.0;  // sliced factorization time after which its rate is trusted

  std::unique_ptr<System> system_;  // the reordering under way
  bool first_build_requested_ = false;
  bool relinearizes_ = false;
  int64_t due_ = 0;        // the update() call at which it replaces the current system
  double spent_ms_ = 0.0;  // time its slices have taken so far
  double work_ms_ = 0.0;   // time the last reordering took from its first slice to its installation
  double rate_ = 0.0;      // row work per millisecond of the last reordering's sliced factorization (row_work)
  std::chrono::steady_clock::time_point update_started_{};
};

/// Begins a requested first build: the pending variables their factors determine and the factors all of whose
/// variables are then in enter at their current estimates (admission.hpp, as for a rebuild), and the scheduler
/// begins their system (ordering and H's pattern).
void begin_first_build(SmootherState& s);
/// An update while a first build is under way: begins it when requested; then, unless it is due, works this
/// update's slice of it and returns true (the update has nothing else to do: nothing can be solved yet).
bool first_build_slice(SmootherState& s);

}  // namespace sextant::graph::smoother
