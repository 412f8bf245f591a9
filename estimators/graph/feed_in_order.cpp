#include "estimators/graph/feed_in_order.hpp"

#include "estimators/graph/optimizer.hpp"

#include <algorithm>
#include <chrono>

namespace sextant::graph {

namespace {

// The batch optimum's chi2 of the smoother's factors so far, from its current estimate: what its online answer is
// measured against.
double batch_chi2(const IncrementalSmoother& smoother) {
  FactorGraph copy;
  for (const Variable& v : smoother.graph().variables()) copy.add_variable(v);
  for (const auto& f : smoother.graph().factors()) copy.add_factor(f->clone());
  OptimizerOptions o;
  o.kernel = smoother.options().kernel;
  o.kernel_width = smoother.options().kernel_width;
  const OptimizerSummary summary = optimize(copy, o);
  return summary.usable() ? summary.final_chi2 : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

FeedResult feed_in_order(const FactorGraph& graph, IncrementalSmoother& smoother, const FeedOptions& options) {
  FeedResult r;
  const auto& vars = graph.variables();
  // The step of each factor: its latest pose (factors without a pose go with the first step).
  std::vector<std::vector<size_t>> steps(vars.size() + 1);
  for (size_t fi = 0; fi < graph.factors().size(); ++fi) {
    int latest = -1;
    for (int v : graph.factors()[fi]->variables())
      if (vars[static_cast<size_t>(v)].is_pose()) latest = std::max(latest, v);
    steps[static_cast<size_t>(std::max(latest, 0))].push_back(fi);
  }
  std::vector<int> to_smoother(vars.size(), -1);
  const auto last_step = std::find_if(steps.rbegin(), steps.rend(), [](const auto& s) { return !s.empty(); });
  const std::vector<size_t>* last = last_step == steps.rend() ? nullptr : &*last_step;
  for (const auto& step : steps) {
    if (step.empty()) continue;
    for (size_t fi : step) {
      const Factor& f = *graph.factors()[fi];
      const auto& fv = f.variables();
      for (size_t k = 0; k < fv.size(); ++k) {
        const size_t v = static_cast<size_t>(fv[k]);
        if (to_smoother[v] >= 0) continue;
        Variable init = vars[v];
        const auto* rel = dynamic_cast<const RelativePoseFactor*>(&f);
        if (rel != nullptr && !init.fixed) {
          const size_t other = static_cast<size_t>(fv[1 - k]);
          if (to_smoother[other] >= 0) {
            const Variable& known = smoother.graph().variables()[static_cast<size_t>(to_smoother[other])];
            if (rel->planar())
              init.pose2 = k == 1 ? known.pose2 * rel->measurement2() : known.pose2 * rel->measurement2().inverse();
            else
              init.pose3 = k == 1 ? known.pose3 * rel->measurement3() : known.pose3 * rel->measurement3().inverse();
          }
        }
        to_smoother[v] = smoother.add_variable(init);
        r.start.add_variable(init);
      }
      std::vector<int> mapped;
      for (int v : fv) mapped.push_back(to_smoother[static_cast<size_t>(v)]);
      smoother.add_factor(f.rebind(mapped));
      r.start.add_factor(f.rebind(mapped));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const IncrementalStatus st = smoother.update();
    r.step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    r.steps.push_back({st, smoother.factor_nonzeros(), smoother.reordering()});
    if (options.chi2) r.steps.back().chi2 = smoother.chi2();
    if (options.reference_every > 0 &&
        (r.steps.size() % static_cast<size_t>(options.reference_every) == 0 || &step == last))
      r.steps.back().batch_chi2 = batch_chi2(smoother);
    r.rebuilds += st.rebuilt ? 1 : 0;
    r.relinearized_factors += st.relinearized_factors;
    r.deferred_at_end = st.deferred_variables;
    if (!st.ok) {
      r.ok = false;
      r.message = st.message;
      return r;
    }
  }
  // The final estimate is the exact solution of the last linearization; its cost is counted in the last step.
  const auto t0 = std::chrono::steady_clock::now();
  smoother.refresh_estimate();
  if (!r.step_ms.empty())
    r.step_ms.back() += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace sextant::graph
