#include "estimators/graph/smoother/reorder_scheduler.hpp"

#include "estimators/graph/smoother/admission.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <algorithm>

namespace sextant::graph::smoother {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
}  // namespace

void ReorderScheduler::begin(SmootherState& s, bool relinearizes) {
  std::vector<char> in(s.graph.variables().size(), 0);
  for (size_t v = 0; v < s.pos.size(); ++v) in[v] = s.pos[v] >= 0;
  begin(s, in);
  relinearizes_ = relinearizes;
}

void ReorderScheduler::begin(SmootherState& s, const std::vector<char>& in) {
  first_build_requested_ = false;
  relinearizes_ = false;
  system_ = begin_system(s, in, false);
  due_ = s.update_calls + s.options.reorder_spread;
  spent_ms_ = 0.0;
}

ReorderScheduler::Finished ReorderScheduler::finish(SmootherState& s) {
  std::unique_ptr<System> sys = std::move(system_);
  const auto started = Clock::now();
  advance(s, *sys, {});
  work_ms_ = spent_ms_ + ms_since(started);
  if (sys->sliced_ms > kRateAfterMs) rate_ = sys->sliced_work / sys->sliced_ms;
  if (!sys->error.empty()) return Finished::kFailed;
  if (!install(s, *sys)) return Finished::kCholmodFailed;
  ++s.rebuilds;
  return Finished::kInstalled;
}

void ReorderScheduler::work(SmootherState& s, bool began_now) {
  if (!system_) return;
  // What is left of reorder_slice_ms after this update's own work, and at least this update's even share of the
  // work left, so that little is left for the update that installs it: with the first rule alone, city10000's
  // updates during a reordering (4-6 ms each, the factor being at its fullest) left it nearly all, 40-70 ms.  The
  // update that began it has paid the ordering.
  const auto now = Clock::now();
  const double own = std::chrono::duration<double, std::milli>(now - update_started_).count();
  const int64_t left = std::max<int64_t>(1, due_ - s.update_calls);
  const double share = began_now ? 0.0 : remaining_ms() / static_cast<double>(left);
  const auto deadline =
      now + std::chrono::duration<double, std::milli>(std::max(s.options.reorder_slice_ms - own, share));
  advance(s, *system_, [&] { return std::chrono::duration<double, std::milli>(deadline - Clock::now()).count(); });
  spent_ms_ += ms_since(now);
}

double ReorderScheduler::remaining_ms() const {
  const System& sys = *system_;
  // Once the row work is known and the last reordering's rate measured: the factorization's
  // remaining rows at that rate, with a tenth to spare for what the estimate leaves out (the conversion to LDL'
  // and the forward solve); before that, the last reordering's time with a quarter to spare, less what this one
  // has spent.
  if (!sys.row_work.empty() && rate_ > 0)
    return 1.1 * (sys.row_work.back() - sys.row_work[std::min(sys.factorized, sys.row_work.size() - 1)]) / rate_;
  return std::max(0.0, 1.25 * work_ms_ - spent_ms_);
}

void begin_first_build(SmootherState& s) {
  IncrementalStatus admitted;
  s.reorder.begin(s, admit_for_rebuild(s, admitted));
}

bool first_build_slice(SmootherState& s) {
  const bool begins = s.reorder.first_build_requested();
  if (begins) begin_first_build(s);
  if (s.reorder.due(s.update_calls)) return false;
  s.reorder.work(s, begins);
  return true;
}

}  // namespace sextant::graph::smoother
